"""Brute force: enumerate every simple route and keep the shortest per number of corrections.

Deliberately naive so that it is obviously right: a depth-first walk over simple routes that
prunes only a prefix already past a limit (errors only grow along a prefix until a reset, and the
violated arrival has already happened, so every extension of it is infeasible too). No length
bounds, no dominance. The arithmetic mirrors ``evaluate_route`` step by step (same distances,
same order of additions, same comparison in metres flown against ``Parameters.limits_m``), so a
boundary case is decided identically. Exponential: for scenarios of up to about 9 correction
points.

With ``Scenario.capture_vertical`` (a design turbulence) a route must also fit every capture
(docs/model.md, "Turbulence in the plan"): at each V, H and B point, every correction outcome
arriving within the limits (the unreliable points' failures clipped to r) passes within the
capture radius, its vertical error plus the point's vertical allowance and the tracking
allowance added as ``capture_check`` adds them.

With ``Scenario.endurance`` a route's flight time in the design wind (``flight_time``'s leg
times, summed leg by leg as ``route_minutes`` sums them) must be within it (docs/model.md,
"Endurance in the plan"); a prefix already beyond it is dropped (flight time only grows).
"""

from __future__ import annotations

import math

import numpy as np

from gcs_planner.aircraft.profile import TRACKING_ALLOWANCE_M
from gcs_planner.baselines import Front
from gcs_planner.core.flight_time import leg_seconds
from gcs_planner.scenario.model import Kind, Scenario


def distance_matrix(scenario: Scenario) -> np.ndarray:
    """Straight distances [i, j] = |P_j − P_i|, computed the way ``straight_legs`` computes them
    (difference, then ``np.linalg.norm`` over the coordinates) so that the floats agree."""
    xyz = scenario.xyz
    return np.linalg.norm(xyz[None, :, :] - xyz[:, None, :], axis=2)


def front_from_best(best: dict[int, tuple[float, tuple[int, ...]]]) -> Front:
    """Pareto front from the shortest route with exactly k corrections, for each k found:
    keep k only where the minimum length over ≤ k corrections strictly decreases."""
    front: Front = []
    for k in sorted(best):
        length, route = best[k]
        if not front or length < front[-1][0]:
            front.append((length, k, route))
    return front


def brute_force_front(scenario: Scenario, max_corrections: int | None = None) -> Front:
    """The exact (length, corrections) Pareto front over simple routes, by enumeration.

    ``max_corrections`` caps the depth (None: all correction points may be used). Returns an
    empty list when no feasible route exists.
    """
    dist = distance_matrix(scenario).tolist()
    params = scenario.params
    kinds = [Kind(int(k)) for k in scenario.kind]
    limits = [params.limits_m(k) for k in kinds]
    start, end = scenario.start, scenario.end
    corrections = [i for i, k in enumerate(kinds) if k in (Kind.V, Kind.H)]
    depth_cap = len(corrections) if max_corrections is None else max(0, max_corrections)

    best: dict[int, tuple[float, tuple[int, ...]]] = {}
    path = [start]
    used = [False] * scenario.n
    used[start] = True

    vertical = scenario.capture_vertical
    residual = params.residual_m
    endurance = math.inf if scenario.endurance is None else float(scenario.endurance)

    def flown_for(seconds: float, i: int, j: int) -> float:
        """The seconds of flight after the leg i -> j (no ground speed: forever)."""
        return seconds + leg_seconds(scenario, i, j, dist[i][j])

    def outcomes(j: int, states: frozenset, d: float) -> frozenset | None:
        """The correction outcomes after arriving at ``j``, None when a capture does not fit."""
        lim_v, lim_h = limits[j]
        arrived = [(v + d, h + d) for v, h in states if v + d <= lim_v and h + d <= lim_h]
        if vertical is None:
            return frozenset()
        if not arrived:
            return None
        z, unit = vertical[j] / scenario.error_unit, scenario.error_unit
        worst = max(math.hypot(v * params.delta + z, h * params.delta) for v, h in arrived) * unit
        if worst + TRACKING_ALLOWANCE_M > scenario.capture_radius:
            return None
        # The outcomes that can happen: a correction that never works (p = 0) leaves only its
        # failure, one that always does (p = 1) only its success (as the probability model).
        fails = bool(scenario.unreliable[j]) and kinds[j] in (Kind.V, Kind.H)
        works = not fails or params.p_success > 0.0
        out = set()
        for v, h in arrived:
            if works:
                out.add(
                    (0.0, h) if kinds[j] == Kind.V else (v, 0.0) if kinds[j] == Kind.H else (v, h)
                )
            if fails and params.p_success < 1.0:
                out.add((min(v, residual), h) if kinds[j] == Kind.V else (v, min(h, residual)))
        return frozenset(out)

    def visit(i: int, dv: float, dh: float, length: float, states: frozenset, s: float) -> None:
        row = dist[i]
        # B ends the route: record it, never extend past it.
        d = row[end]
        lim_v, lim_h = limits[end]
        in_time = endurance == math.inf or flown_for(s, i, end) / 60.0 <= endurance
        if dv + d <= lim_v and dh + d <= lim_h and in_time and outcomes(end, states, d) is not None:
            k = len(path) - 1
            total = length + d
            if k not in best or total < best[k][0]:
                best[k] = (total, (*path, end))
        if len(path) - 1 >= depth_cap:
            return
        for j in corrections:
            if used[j]:
                continue
            d = row[j]
            arrive_v, arrive_h = dv + d, dh + d
            lim_v, lim_h = limits[j]
            if arrive_v > lim_v or arrive_h > lim_h:
                continue
            after = outcomes(j, states, d)
            if after is None:
                continue
            seconds = 0.0 if endurance == math.inf else flown_for(s, i, j)
            if seconds / 60.0 > endurance:
                continue
            if kinds[j] == Kind.V:
                arrive_v = 0.0
            else:
                arrive_h = 0.0
            used[j] = True
            path.append(j)
            visit(j, arrive_v, arrive_h, length + d, after, seconds)
            path.pop()
            used[j] = False

    visit(start, 0.0, 0.0, 0.0, frozenset([(0.0, 0.0)]), 0.0)
    return front_from_best(best)
