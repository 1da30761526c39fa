"""The front of contingency policies over (F1, F2, F3) (docs/model.md, "Contingency policies").

Exact by dynamic programming over flight states on small scenarios: a policy from a state
(point, heading, errors, points flown) is a segment to the next unreliable point or B, then one
policy per outcome from the state each outcome leaves. A parent's objectives are monotone in its
children's (F1 and F2 add the segment's to the larger of the two children's, F3 is
p·F3(success) + (1 − p)·F3(failure)), so keeping only each state's non-dominated policies loses
no policy of the front. Lost outcomes still count in F1 and F2 (their planned path is the
mission the aircraft carries; ``contingency.evaluate``), so lost states are searched too, with
their error state dropped (nothing below them arrives).

On larger scenarios the front is approximated: :func:`replanned_front` replans each route of
the route front on failure (``core/replan.py``) and keeps the non-dominated policies, routes
included, so it dominates the route front; it is not proven optimal over all policies.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gcs_planner.core.contingency import Policy, PolicyValue, _start_heading, _unreliable, evaluate
from gcs_planner.core.probability import PROB_EPS, outcomes
from gcs_planner.core.route import Route
from gcs_planner.errors import GcsPlannerError
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

# The dynamic programme enumerates segments and states: beyond this many correction points it
# refuses (the replanned front is the answer there).
EXACT_MAX_POINTS = 7


@dataclass(frozen=True)
class PolicyPoint:
    """One policy of a front and its objectives."""

    policy: Policy
    value: PolicyValue


def pareto(values: Sequence[tuple[float, int, float]], eps: float = 1e-9) -> list[int]:
    """Indices of the non-dominated (F1, F2, F3) triples (F1, F2 minimised, F3 maximised),
    one per distinct value, sorted by F2 then F1."""
    keep: list[int] = []
    for i, (l1, c1, p1) in enumerate(values):
        dominated = False
        for j, (l2, c2, p2) in enumerate(values):
            if j == i:
                continue
            weakly = l2 <= l1 + eps * max(1.0, l1) and c2 <= c1 and p2 >= p1 - PROB_EPS
            same = abs(l2 - l1) <= eps * max(1.0, l1) and c2 == c1 and abs(p2 - p1) <= PROB_EPS
            if weakly and (not same or j < i):
                dominated = True
                break
        if not dominated:
            keep.append(i)
    return sorted(keep, key=lambda i: (values[i][1], values[i][0], -values[i][2]))


def exact_policy_front(
    scenario: Scenario, *, max_points: int = EXACT_MAX_POINTS
) -> list[PolicyPoint]:
    """Every non-dominated policy value, each with one policy attaining it (F3 > 0 only: a
    policy that cannot arrive is no answer). Raises GcsPlannerError beyond ``max_points``
    correction points."""
    corr = [j for j in range(scenario.n) if int(scenario.kind[j]) in (Kind.V, Kind.H)]
    if len(corr) > max_points:
        raise GcsPlannerError(
            f"the exact policy front enumerates policies and stops at {max_points} correction "
            f"points; this scenario has {len(corr)}"
        )
    model = scenario_leg_model(scenario)
    params = scenario.params
    xyz = scenario.xyz
    end = scenario.end
    p = params.p_success
    memo: dict[tuple, list[tuple[float, int, float, Policy]]] = {}

    def prune(
        options: list[tuple[float, int, float, Policy]],
    ) -> list[tuple[float, int, float, Policy]]:
        return [options[i] for i in pareto([o[:3] for o in options])]

    def front(at: int, heading, v: float, h: float, visited: frozenset[int], lost: bool):
        key = (at, None if heading is None else np.asarray(heading).tobytes(),
               None if lost else (v, h), visited)  # fmt: skip
        if key in memo:
            return memo[key]
        options: list[tuple[float, int, float, Policy]] = []

        def segment(j_at: int, hd, v: float, h: float, lost: bool, length: float, k: int,
                    pts: tuple[int, ...], used: frozenset[int]) -> None:  # fmt: skip
            for j in [*corr, end]:
                if j in used:
                    continue
                leg = model.leg(xyz[j_at], hd, xyz[j])
                d = float(leg.length)
                kind = Kind(int(scenario.kind[j]))
                total = length + d
                nk = k + (kind in (Kind.V, Kind.H))
                flyable = bool(leg.reachable) and math.isfinite(d)
                nv, nh, now_lost = v + d, h + d, lost or not flyable
                v_lim, h_lim = params.limits_m(kind)
                if not now_lost and not (nv <= v_lim and nh <= h_lim):
                    now_lost = True
                # As route_trajectory: after a leg that cannot be flown, its start heading.
                out = (
                    hd
                    if not flyable or leg.heading_out is None
                    else np.asarray(leg.heading_out, float)
                )
                path = (*pts, j)
                if j == end:
                    options.append((total, nk, 0.0 if now_lost else 1.0, Policy(path)))
                    continue
                if _unreliable(scenario, j):
                    ok, fail = outcomes(nv, nh, kind, params.residual_m)
                    seen = used | {j}
                    kids_ok = front(j, out, *ok, seen, now_lost)
                    kids_fail = front(j, out, *fail, seen, now_lost)
                    for lo, co, po, pol_o in kids_ok:
                        for lf, cf, pf, pol_f in kids_fail:
                            prob = 0.0 if now_lost else p * po + (1.0 - p) * pf
                            options.append((total + max(lo, lf), nk + max(co, cf), prob,
                                            Policy(path, pol_o, pol_f)))  # fmt: skip
                    continue
                if kind == Kind.V:
                    nv = 0.0
                elif kind == Kind.H:
                    nh = 0.0
                segment(j, out, nv, nh, now_lost, total, nk, path, used | {j})

        segment(at, heading, v, h, lost, 0.0, 0, (at,), visited)
        memo[key] = result = prune(options)
        return result

    start_heading = _start_heading(scenario)
    v0, h0 = scenario.initial_errors
    found = front(scenario.start, start_heading, v0, h0, frozenset({scenario.start}), False)
    return [PolicyPoint(pol, evaluate(scenario, pol)) for _, _, prob, pol in found if prob > 0.0]


def replanned_front(
    scenario: Scenario, routes: Sequence[Route], policies: Sequence[Policy]
) -> list[PolicyPoint]:
    """The non-dominated of ``routes`` (as policies) and ``policies``."""
    every = [Policy.from_route(scenario, r) for r in routes] + list(policies)
    points = [PolicyPoint(pol, evaluate(scenario, pol)) for pol in every]
    points = [pt for pt in points if pt.value.probability > 0.0]
    keep = pareto([(pt.value.length, pt.value.corrections, pt.value.probability) for pt in points])
    return [points[i] for i in keep]
