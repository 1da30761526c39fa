"""Replanning on failure: a route made a policy that, at each failed fix, takes the best
continuation from the state reached (docs/model.md, "Contingency policies").

At every unreliable point of the route, on every outcome path (each with its own errors), the
failure branch is a route from the state after the failed fix: that point, the heading the
aircraft arrives on, the errors the failure leaves, every point already flown excluded. It is
planned by the planner itself (``core/from_state.py``: the state's scenario, every search
unchanged), and chosen by the plan's own rule; it replaces the route's own continuation only if
it is more likely to arrive, or as likely and shorter, so the policy is never worse than the
route. With ``levels`` > 1 a branch is replanned again at its own unreliable points.

The brute-force engine (simple continuations enumerated, the most reliable then shortest) is
kept as the tests' independent reference on tiny scenarios.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from gcs_planner.core.contingency import (
    Heading,
    Policy,
    _chain,
    _Evaluator,
    _start_heading,
    _unreliable,
    validate,
)
from gcs_planner.core.from_state import FlightState, original_points, state_scenario
from gcs_planner.core.probability import PROB_EPS, outcomes, propagate
from gcs_planner.core.route import Route
from gcs_planner.errors import GcsPlannerError, InfeasibleError
from gcs_planner.geometry.legs import LegModel, scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

# Brute force over simple continuations grows factorially: the reference engine refuses
# scenarios with more correction points than this.
BRUTE_FORCE_MAX_POINTS = 12
# Seconds each continuation's plan may take, counted as the plan's own are (core/budget.py: the
# process's CPU time): its statement says what it proved. A continuation is a plan from a
# failure state over fewer points than the mission's (dataset 2's are proven in a fraction of a
# second each); the limit bounds one that is not, so a policy of a hundred continuations stays
# within what a planner waits for.
DEFAULT_BRANCH_TIME_LIMIT = 5.0
# How deep ``plan --policy`` replans: the route's own failures, then its branches' own. A
# branch is a fixed route from its failure state until it is replanned at its own failures too;
# beyond two levels the branches' branches seldom change (docs/flying-policies.md: dataset 2
# within 15°/15° gains from one level to two, not from two to three).
DEFAULT_POLICY_LEVELS = 2


@dataclass
class Replanned:
    """A replanned policy and how its branches were found."""

    policy: Policy
    branches: int = 0  # failure branches that replaced the route's own continuation
    plans: int = 0  # continuations planned (one per distinct failure state)
    unproven: list[str] = field(default_factory=list)  # branch plans not proven optimal


Continuation = Callable[[FlightState], tuple[tuple[int, ...] | None, bool]]


def brute_continuation(scenario: Scenario) -> Continuation:
    """Brute force over simple continuations from a state: the most likely to arrive, then the
    shortest. Returns (points or None, proven: always True)."""
    corrections = int(np.count_nonzero(np.isin(scenario.kind, (Kind.V, Kind.H))))
    if corrections > BRUTE_FORCE_MAX_POINTS:
        raise GcsPlannerError(
            f"replanning by brute force enumerates continuations and stops at "
            f"{BRUTE_FORCE_MAX_POINTS} correction points; this scenario has {corrections}"
        )
    model = scenario_leg_model(scenario)

    def continuation(state: FlightState) -> tuple[tuple[int, ...] | None, bool]:
        heading = None if state.heading is None else np.asarray(state.heading, float)
        found = _most_reliable(scenario, model, state.point, state.v, state.h, heading,
                               state.visited)  # fmt: skip
        return (None if found is None else tuple(found)), True

    return continuation


def search_continuation(
    scenario: Scenario,
    *,
    choice: str = "most-reliable",
    min_probability: float = 0.0,
    time_limit: float | None = DEFAULT_BRANCH_TIME_LIMIT,
) -> Continuation:
    """The planner's continuation from a state (its front from the state's scenario, the route
    chosen by ``choice`` and ``min_probability`` as a plan chooses). Returns (points in the
    scenario's indices or None when no route is left, proven optimal)."""
    from gcs_planner.core.planner import plan  # the planner imports this module's callers

    # One plan per state, whichever route reached it: the routes of a front share their first
    # points (dataset 2's four share seven), so their failure states recur from route to route,
    # and a continuation depends on the state alone (core/from_state.py).
    planned: dict[FlightState, tuple[tuple[int, ...] | None, bool]] = {}

    def continuation(state: FlightState) -> tuple[tuple[int, ...] | None, bool]:
        got = planned.get(state)
        if got is None:
            got = planned[state] = _plan_from(state)
        return got

    def _plan_from(state: FlightState) -> tuple[tuple[int, ...] | None, bool]:
        sub, indices = state_scenario(scenario, state)
        try:
            got = plan(sub, choice=choice, min_probability=min_probability, time_limit=time_limit)
        except InfeasibleError:
            return None, True
        return original_points(indices, got.route.points), bool(got.proven()[got.chosen])

    return continuation


def replan_on_failure(
    scenario: Scenario,
    route: Route | Sequence[int],
    *,
    continuation: Continuation | None = None,
    levels: int = 1,
    progress: Callable[[int], None] | None = None,
) -> Replanned:
    """The route as a policy whose failure branches are replanned (see the module's docstring).

    ``continuation``: how a branch is found from a state (default: ``search_continuation``,
    the most reliable continuation). ``levels``: how deep branches are replanned again (1: the
    route's own failures only). ``progress(plans)`` is called after each continuation planned.
    """
    if levels < 1:
        raise ValueError("levels must be >= 1")
    points = [int(p) for p in (route.points if isinstance(route, Route) else route)]
    base = Policy.from_route(scenario, points)
    validate(scenario, base)
    find = search_continuation(scenario) if continuation is None else continuation
    ev = _Evaluator(scenario)
    params = scenario.params
    out = Replanned(base)
    memo: dict[tuple, Policy] = {}
    found_memo: dict[tuple, tuple[int, ...] | None] = {}

    def better(a: Policy, b: Policy, v: float, h: float, heading: Heading) -> bool:
        pa, pb = ev.value(a, v, h, heading)[0], ev.value(b, v, h, heading)[0]
        if pa > pb + PROB_EPS:
            return True
        return pa >= pb - PROB_EPS and ev.shape(a, heading)[0] < ev.shape(b, heading)[0]

    def build(node: Policy, v: float, h: float, heading: Heading, visited: frozenset[int],
              level: int) -> Policy:  # fmt: skip
        key = (id(node), v, h, visited, level)
        if key in memo:
            return memo[key]
        legs, end_heading = ev.legs(node, heading)
        visited = visited | set(node.points)
        result = node
        arrived = not node.leaf
        for j, leg in zip(node.points[1:], legs, strict=True):
            v += leg
            h += leg
            kind = Kind(int(scenario.kind[j]))
            v_lim, h_lim = params.limits_m(kind)
            if not (math.isfinite(leg) and v <= v_lim and h <= h_lim):
                arrived = False  # lost before the branch: no outcome below matters
                break
            if j != node.points[-1]:
                if kind == Kind.V:
                    v = 0.0
                elif kind == Kind.H:
                    h = 0.0
        if arrived:
            at = node.points[-1]
            ok_state, fail_state = outcomes(v, h, Kind(int(scenario.kind[at])), params.residual_m)
            on_success = build(node.on_success, *ok_state, end_heading, visited, level)
            own = build(node.on_failure, *fail_state, end_heading, visited, level)
            on_failure = own
            state = FlightState(
                at,
                None if end_heading is None else tuple(float(c) for c in end_heading),
                fail_state[0],
                fail_state[1],
                visited,
            )
            skey = (at, fail_state, state.heading, visited)
            if skey not in found_memo:
                found, proven = find(state)
                found_memo[skey] = found
                out.plans += 1
                if not proven:
                    out.unproven.append(scenario.ids[at])
                if progress is not None:
                    progress(out.plans)
            found = found_memo[skey]
            if found is not None and tuple(found) != tuple((at, *success_path(own))):
                candidate = _chain(scenario, list(found))
                if level < levels:
                    candidate = build(candidate, *fail_state, end_heading, visited, level + 1)
                if better(candidate, own, *fail_state, end_heading):
                    on_failure = candidate
                    out.branches += 1
            result = Policy(node.points, on_success, on_failure)
        memo[key] = result
        return result

    out.policy = build(base, *scenario.initial_errors, _start_heading(scenario), frozenset(), 1)
    validate(scenario, out.policy)
    return out


def success_path(node: Policy) -> tuple[int, ...]:
    """The points after ``node``'s first along its success path."""
    pts = node.points[1:]
    while node.on_success is not None:
        node = node.on_success
        pts += node.points[1:]
    return pts


def _most_reliable(
    scenario: Scenario,
    model: LegModel,
    start: int,
    v: float,
    h: float,
    heading: np.ndarray | None,
    visited: frozenset[int],
) -> list[int] | None:
    """Brute force over simple fixed continuations from ``start`` to B: the most likely to
    arrive, then the shortest (None when none can arrive)."""
    params = scenario.params
    xyz = scenario.xyz
    end = scenario.end
    free = [
        j for j in range(scenario.n)
        if int(scenario.kind[j]) in (Kind.V, Kind.H) and j not in visited
    ]  # fmt: skip
    best: list = [None, 0.0, math.inf]

    def dfs(at, states, heading, length, path, used):
        for j in [*free, end]:
            if j in used:
                continue
            leg = model.leg(xyz[at], heading, xyz[j])
            d = float(leg.length)
            if not (leg.reachable and math.isfinite(d)):
                continue
            kind = Kind(int(scenario.kind[j]))
            new, mass = propagate(states, d, kind, _unreliable(scenario, j), params)
            total = length + d
            # Mass only falls and length only grows along a path: prune what cannot beat best.
            if mass <= 0.0 or mass < best[1] - PROB_EPS:
                continue
            if mass <= best[1] + PROB_EPS and total >= best[2]:
                continue
            if j == end:
                if mass > best[1] + PROB_EPS or total < best[2]:
                    best[:] = [[*path, j], mass, total]
                continue
            dfs(j, new, np.asarray(leg.heading_out, float), total, [*path, j], used | {j})

    dfs(start, {(v, h): 1.0}, heading, 0.0, [start], frozenset())
    return best[0]
