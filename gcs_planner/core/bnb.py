"""Branch and bound over simple routes, for what the layered search cannot carry in a label:
the heading (turns: the flown length of a leg depends on the whole route before it) and the
distribution of error states (uncertain corrections).

Labels are whole partial routes (point, heading, flown length, corrections, error-state
distribution, path), explored best-first by f = L + G_j(e), G the admissible cost-to-go of
``cost_to_go``. A label is pruned when a route already found is at least as good on every
objective it can still reach: length <= f, corrections <= k, probability >= the mass still
alive. When the queue empties, the routes found are exactly the Pareto front under the model —
the proof is the exhausted search. If a label budget stops it earlier, every front point gets
the lower bound that the open labels still allow, and the gap is reported, never hidden.
"""

from __future__ import annotations

import heapq
import itertools
import math
import time
from dataclasses import dataclass

import numpy as np

from gcs_planner.core.cost_to_go import cost_to_go
from gcs_planner.core.probability import propagate
from gcs_planner.core.reach import build_reach_graph
from gcs_planner.core.route import Leg, Route, evaluate_route
from gcs_planner.geometry.dubins import cs_lengths
from gcs_planner.geometry.trajectory import route_trajectory
from gcs_planner.scenario.model import Kind, Scenario

DEFAULT_MAX_LABELS = 5_000


@dataclass(frozen=True)
class Found:
    length: float
    corrections: int
    probability: float
    points: tuple[int, ...]


@dataclass
class BnbResult:
    front: list[Found]
    lower_bounds: list[float]
    optimal: bool
    labels: int
    seconds: float
    exhausted: bool
    # Over the open labels no front point dominates: how many, and the least length they can
    # still reach (inf when there are none: the front is then complete).
    open_labels: int = 0
    open_bound: float = math.inf


# Probabilities reached along different routes are products taken in different orders: equal
# values may differ in the last bits, and must still compare equal.
PROB_EPS = 1e-12


def _dominated(found: list[Found], length: float, k: int, prob: float) -> bool:
    """Whether a found route is at least as good as (length, k, prob) on every objective."""
    for f in found:
        if f.corrections <= k and f.probability >= prob - PROB_EPS and f.length <= length:
            return True
    return False


def bnb_front(
    scenario: Scenario,
    *,
    probability: bool,
    max_corrections: int | None = None,
    max_labels: int = DEFAULT_MAX_LABELS,
) -> BnbResult:
    """Exact Pareto front of (length, corrections[, probability]) with the scenario's turning
    radius, by best-first branch and bound. ``probability`` False treats every correction as
    certain (the two-objective model)."""
    t0 = time.perf_counter()
    params = scenario.params
    R = params.turn_radius
    graph = build_reach_graph(scenario)
    G = cost_to_go(scenario, graph)
    kmax = scenario.n - 2 if max_corrections is None else max_corrections
    xyz = scenario.xyz
    kinds = scenario.kind
    kind_of = [Kind(int(c)) for c in kinds]  # Enum construction is slow in the inner loop
    unreliable = scenario.unreliable if probability else np.zeros(scenario.n, dtype=bool)
    start, end = graph.start, graph.end
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)

    found: list[Found] = []
    counter = itertools.count()
    # Entry: (f, tiebreak, L, node, k, states, heading, path)
    heap: list = [
        (
            float(graph.to_end[start]),  # A carries no error: |A - B| is the bound
            next(counter),
            0.0,
            start,
            0,
            {(0.0, 0.0): 1.0},
            heading_a,
            (start,),
        )
    ]
    labels = 0
    exhausted = True
    while heap:
        f, _, L, node, k, states, heading, path = heapq.heappop(heap)
        mass = sum(states.values())
        if _dominated(found, f, k, mass):
            continue
        labels += 1
        if labels > max_labels:
            heapq.heappush(heap, (f, next(counter), L, node, k, states, heading, path))
            exhausted = False
            break
        lo, hi = graph.indptr[node], graph.indptr[node + 1]
        targets = graph.target[lo:hi].astype(np.int64)
        straight = graph.length[lo:hi]
        if heading is None or R == 0:
            flown = straight
            headings = None
        else:
            flown, headings = cs_lengths(xyz[node], heading, xyz[targets], R)
        v_min = min(s[0] for s in states)
        h_min = min(s[1] for s in states)
        ok = (v_min + flown <= graph.lim_v[targets]) & (h_min + flown <= graph.lim_h[targets])
        for idx in np.flatnonzero(ok):
            j = int(targets[idx])
            if j in path:
                continue
            d = float(flown[idx])
            is_end = j == end
            if not is_end and k + 1 > kmax:
                continue
            new_states, _ = propagate(states, d, kind_of[j], bool(unreliable[j]), params)
            if not new_states:
                continue
            new_mass = sum(new_states.values())
            nL = L + d
            if is_end:
                new_mass = min(1.0, new_mass)
                if not _dominated(found, nL, k, new_mass):
                    new = Found(nL, k, new_mass, path + (j,))
                    found = [
                        g
                        for g in found
                        if not _dominated([new], g.length, g.corrections, g.probability)
                    ]
                    found.append(new)
                continue
            is_v = kind_of[j] == Kind.V
            e_min = min(st[1] if is_v else st[0] for st in new_states)
            h = G(j, e_min)  # G is non-decreasing in e: the least carried error bounds all
            nf = nL + h
            if not math.isfinite(nf) or _dominated(found, nf, k + 1, new_mass):
                continue
            if headings is not None:
                new_heading = headings[idx]
            elif R > 0:
                new_heading = (xyz[j] - xyz[node]) / max(float(straight[idx]), 1e-300)
            else:
                new_heading = None
            heapq.heappush(
                heap, (nf, next(counter), nL, j, k + 1, new_states, new_heading, path + (j,))
            )
    found.sort(key=lambda g: (g.corrections, g.length))
    live = [e for e in heap if not _dominated(found, e[0], e[4], sum(e[5].values()))]
    open_bound = min((e[0] for e in live), default=math.inf)
    heap = live
    lower = []
    for g in found:
        lb = g.length
        for entry in heap:
            ef, ek, est = entry[0], entry[4], entry[5]
            if ek <= g.corrections and sum(est.values()) >= g.probability:
                lb = min(lb, ef)
        lower.append(lb)
    complete = not live
    return BnbResult(
        found, lower, complete, labels, time.perf_counter() - t0, exhausted, len(live), open_bound
    )


def flown_route(scenario: Scenario, points: tuple[int, ...]) -> Route:
    """Re-evaluate a route with the scenario's turning radius, independently of the search."""
    R = scenario.params.turn_radius
    heading = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)
    traj = route_trajectory(scenario.xyz[list(points)], R, heading)
    legs = [Leg(leg.length, leg.arc_length, leg.arc_angle) for leg in traj.legs]
    return evaluate_route(scenario, points, legs, turn_radius=R)
