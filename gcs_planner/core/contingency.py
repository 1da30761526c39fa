"""Contingency policies (docs/model.md, "Contingency policies"): routes that branch at unreliable
points on whether the correction took.

A :class:`Policy` is a tree. Each node is a segment of scenario point indices, its first point the
point the aircraft is at (A at the root) and its last the next unreliable point or B. At an
unreliable point it has two children, ``on_success`` and ``on_failure``, each starting there.

:func:`evaluate` computes a policy's objectives exactly over its outcome tree, flying every leg
with the scenario's own leg model exactly as a route is flown (``route_trajectory``, the heading
carried from the previous leg), so a fixed route converted with :meth:`Policy.from_route` gets
the very probability :func:`gcs_planner.core.probability.success_probability` gives it.

:mod:`gcs_planner.core.replan` makes policies from routes: at each failed fix, the best
continuation from the state reached.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gcs_planner.core.probability import outcomes
from gcs_planner.core.route import Route
from gcs_planner.errors import GcsPlannerError
from gcs_planner.geometry.legs import LegModel, scenario_leg_model
from gcs_planner.geometry.trajectory import route_trajectory
from gcs_planner.scenario.model import Kind, Scenario

Heading = np.ndarray | None


@dataclass(frozen=True, eq=False)
class Policy:
    """One node of a policy tree.

    ``points``: scenario indices flown from the current point (``points[0]``) up to and including
    the next unreliable point or B (``points[-1]``). Both children are given iff ``points[-1]`` is
    an unreliable correction point; each starts at that point. Children may be shared objects
    (a DAG): :meth:`from_route` shares one continuation between both outcomes.
    """

    points: tuple[int, ...]
    on_success: Policy | None = None
    on_failure: Policy | None = None

    @property
    def leaf(self) -> bool:
        return self.on_success is None and self.on_failure is None

    @staticmethod
    def from_route(scenario: Scenario, route: Route | Sequence[int]) -> Policy:
        """A fixed route as a policy whose two children continue identically."""
        points = route.points if isinstance(route, Route) else route
        return _chain(scenario, [int(p) for p in points])


@dataclass(frozen=True)
class PolicyValue:
    """A policy's objectives.

    ``length`` (F1) and ``corrections`` (F2) are maxima over every outcome path of the tree
    (whatever its probability, lost or not: the fuel and the mission the aircraft must carry).
    ``probability`` (F3) is the exact probability of arriving at B within every limit.
    ``expected_length_arrived``: expected flown length given arrival (NaN when it cannot arrive).
    ``expected_flown``: unconditional expected flown length over all outcomes, a lost outcome
    counted up to the point where it was found lost (the leg into that point included; a leg
    that cannot be flown is not).
    """

    length: float
    corrections: int
    probability: float
    expected_length_arrived: float
    expected_flown: float


def _unreliable(scenario: Scenario, j: int) -> bool:
    # As core/probability.py: only a V or H point can fail.
    return bool(scenario.unreliable[j]) and Kind(int(scenario.kind[j])) in (Kind.V, Kind.H)


def _chain(scenario: Scenario, points: list[int]) -> Policy:
    """The fixed path ``points`` (from the current point to B) cut at its unreliable points."""
    if len(points) < 2:
        raise GcsPlannerError("a policy segment has at least two points")
    for k in range(1, len(points) - 1):
        if _unreliable(scenario, points[k]):
            rest = _chain(scenario, points[k:])
            return Policy(tuple(points[: k + 1]), rest, rest)
    return Policy(tuple(points))


def validate(scenario: Scenario, policy: Policy) -> None:
    """Raise GcsPlannerError unless ``policy`` is well formed and every outcome path is simple."""
    if int(scenario.kind[policy.points[0]]) != Kind.A:
        raise GcsPlannerError(f"a policy starts at A, not at point {policy.points[0]}")
    seen: set[tuple[int, frozenset[int]]] = set()  # (node, visited): a DAG is checked once

    def walk(node: Policy, visited: frozenset[int], path: tuple[int, ...]) -> None:
        key = (id(node), visited)
        if key in seen:
            return
        seen.add(key)
        pts = node.points
        if len(pts) < 2:
            raise GcsPlannerError(f"policy segment {pts} has fewer than two points")
        for j in pts:
            if not 0 <= j < scenario.n:
                raise GcsPlannerError(f"policy point {j} is not a point of the scenario")
        for j in pts[1:]:
            if j in visited:
                raise GcsPlannerError(
                    f"policy revisits point {scenario.ids[j]} along outcome path "
                    f"{[scenario.ids[i] for i in path + pts[1:]]}: every branch must be simple"
                )
            visited = visited | {j}
        for j in pts[1:-1]:
            kind = Kind(int(scenario.kind[j]))
            if kind not in (Kind.V, Kind.H):
                raise GcsPlannerError(f"point {scenario.ids[j]} ({kind.name}) inside a segment")
            if _unreliable(scenario, j):
                raise GcsPlannerError(
                    f"unreliable point {scenario.ids[j]} inside segment {pts}: a segment ends "
                    "at the next unreliable point, where the policy branches"
                )
        end = pts[-1]
        if int(scenario.kind[end]) == Kind.B:
            if not node.leaf:
                raise GcsPlannerError("a segment ending at B has no children")
            return
        if not _unreliable(scenario, end):
            raise GcsPlannerError(
                f"segment {pts} ends at {scenario.ids[end]}, neither B nor an unreliable point"
            )
        for name, child in (("on_success", node.on_success), ("on_failure", node.on_failure)):
            if child is None:
                raise GcsPlannerError(f"segment {pts} lacks its {name} branch")
            if child.points[0] != end:
                raise GcsPlannerError(f"{name} branch of {pts} does not start at its last point")
            walk(child, visited, path + pts[1:])

    walk(policy, frozenset({policy.points[0]}), (policy.points[0],))


def _fly(scenario: Scenario, model: LegModel, pts: Sequence[int], heading: Heading):
    """The legs of one segment and the heading it ends with, flown as ``route_trajectory`` flies
    a whole route (so cutting a route into segments changes no bit of its legs)."""
    legs = route_trajectory(
        scenario.xyz[list(pts)], scenario.params.turn_radius, heading, model
    ).legs
    last = legs[-1]
    # As route_trajectory: after a leg that cannot be flown, carry the heading it started with.
    out = last.heading_out if last.reachable else last.heading_in
    return [float(leg.length) for leg in legs], np.asarray(out, dtype=float)


def _start_heading(scenario: Scenario) -> Heading:
    return None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)


class _Evaluator:
    """Exact evaluation over the outcome tree, memoised on (node, errors, heading): a node
    reached in the same state has the same future (the outcomes are independent of the past)."""

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.model = scenario_leg_model(scenario)
        self.params = scenario.params
        self.memo: dict = {}
        self.shape_memo: dict = {}
        self.legs_memo: dict = {}
        # The memos key on id(node): hold every node seen, so that no id is reused by a new
        # node while they live (replanning builds and drops candidate branches).
        self.alive: list[Policy] = []

    def legs(self, node: Policy, heading: Heading):
        key = (id(node), None if heading is None else heading.tobytes())
        got = self.legs_memo.get(key)
        if got is None:
            self.alive.append(node)
            got = self.legs_memo[key] = _fly(self.scenario, self.model, node.points, heading)
        return got

    def shape(self, node: Policy, heading: Heading) -> tuple[float, int]:
        """(longest length, most corrections) over the outcome paths below ``node``."""
        key = (id(node), None if heading is None else heading.tobytes())
        got = self.shape_memo.get(key)
        if got is not None:
            return got
        legs, out = self.legs(node, heading)
        length = sum(legs)
        corr = sum(1 for j in node.points[1:] if int(self.scenario.kind[j]) in (Kind.V, Kind.H))
        if not node.leaf:
            ls, cs = self.shape(node.on_success, out)
            lf, cf = self.shape(node.on_failure, out)
            length, corr = length + max(ls, lf), corr + max(cs, cf)
        self.shape_memo[key] = (length, corr)
        return length, corr

    def value(self, node: Policy, v: float, h: float, heading: Heading):
        """(P(arrive), E[length; arrive], E[flown]) below ``node`` from errors (v, h) in metres
        flown since the last reset, as core/probability.py keeps them."""
        key = (id(node), v, h, None if heading is None else heading.tobytes())
        got = self.memo.get(key)
        if got is not None:
            return got
        sc, params = self.scenario, self.params
        legs, out = self.legs(node, heading)
        flown = 0.0
        result = None
        for j, leg in zip(node.points[1:], legs, strict=True):
            if not math.isfinite(leg):  # cannot be flown: lost here, the leg not flown
                result = (0.0, 0.0, flown)
                break
            v += leg
            h += leg
            flown += leg
            kind = Kind(int(sc.kind[j]))
            v_lim, h_lim = params.limits_m(kind)
            if not (v <= v_lim and h <= h_lim):  # checked on arrival, before the correction
                result = (0.0, 0.0, flown)
                break
            if j == node.points[-1] and not node.leaf:
                break  # the branching correction is applied below, once per outcome
            if kind == Kind.V:
                v = 0.0
            elif kind == Kind.H:
                h = 0.0
        if result is None and node.leaf:
            result = (1.0, flown, flown)
        if result is None:
            p = params.p_success
            ok_state, fail_state = outcomes(
                v, h, Kind(int(sc.kind[node.points[-1]])), params.residual_m
            )
            prob = e_arr = e_flown = 0.0
            # Zero-mass branches are skipped: their value does not matter and may be undefined.
            for mass, child, state in (
                (p, node.on_success, ok_state),
                (1.0 - p, node.on_failure, fail_state),
            ):
                if mass <= 0.0:
                    continue
                cp, ca, cf = self.value(child, state[0], state[1], out)
                prob += mass * cp
                e_arr += mass * (cp * flown + ca)
                e_flown += mass * cf
            result = (prob, e_arr, flown + e_flown)
        self.memo[key] = result
        return result


def evaluate(scenario: Scenario, policy: Policy) -> PolicyValue:
    """F1, F2, F3 and the expected lengths of ``policy`` (see :class:`PolicyValue`), exactly.

    Legs are flown with the scenario's leg model as routes are (straight, airplane or cs3d), each
    segment from the heading the previous one ended with. Raises GcsPlannerError for a malformed
    policy or one whose outcome paths revisit a point.
    """
    validate(scenario, policy)
    ev = _Evaluator(scenario)
    heading = _start_heading(scenario)
    length, corr = ev.shape(policy, heading)
    prob, e_arr, e_flown = ev.value(policy, 0.0, 0.0, heading)
    prob = min(1.0, prob)  # p*m + (1-p)*m may exceed m by an ulp
    arrived = e_arr / prob if prob > 0.0 else math.nan
    return PolicyValue(length, corr, prob, arrived, e_flown)
