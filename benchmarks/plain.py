"""The obvious implementation: a pure-Python label-correcting search, exact and unoptimised.

This is what a careful programmer writes first, and the yardstick the project's search is
measured against. Plain lists, dicts and ``heapq``; no numpy, no bounds towards B, no layers.

- A label is a partial route ending at a point: length L, corrections k, the carried error e
  (metres flown since the last reset of the component the point did not reset; the other one is
  0 right after a correction) and its path.
- Labels are expanded shortest first; every feasible leg makes a new one.
- A label at a point dominates another at the same point when L, e and k are all no larger.
- Every label that can fly on to B within B's limits gives a complete route; the front is the
  shortest complete route per k, kept where the length strictly falls as k grows.

Elementarity by checking the path. The first pass searches walks (labels may re-enter points of
their own path): its front is a lower bound on the front over simple routes, so when every route
on it is simple it *is* that front. Otherwise a second pass forbids re-entering the path and
lets a label dominate only labels whose path contains all of its own points (the visited-set
rule that keeps the search exact over simple routes); it is exponential, which is the point of
the comparison.
"""

from __future__ import annotations

import heapq
import math

from gcs_planner.scenario.model import Kind, Scenario

# A front as the baselines give it: (length, corrections, route) sorted by corrections.
PlainFront = list[tuple[float, int, tuple[int, ...]]]


def _neighbours(
    points: list[tuple[float, float, float]],
    targets: list[int],
    limits: list[tuple[float, float]],
) -> list[list[tuple[int, float]]]:
    """Per point, every target a leg could reach even right after both resets."""
    out: list[list[tuple[int, float]]] = []
    for i, p in enumerate(points):
        row = []
        for j in targets:
            if j == i:
                continue
            d = math.dist(p, points[j])
            if d <= min(limits[j]):
                row.append((j, d))
        out.append(row)
    return out


def plain_front(scenario: Scenario) -> PlainFront:
    """Exact Pareto front of (length, corrections) over simple feasible routes, straight legs."""
    front = plain_search(scenario, elementary=False)
    if all(len(set(route)) == len(route) for _, _, route in front):
        return front
    return plain_search(scenario, elementary=True)


def plain_search(scenario: Scenario, elementary: bool) -> PlainFront:
    """The front over walks (``elementary`` False) or over simple routes (True)."""
    points = [tuple(row) for row in scenario.xyz.tolist()]
    kinds = [Kind(int(k)) for k in scenario.kind.tolist()]
    limits = [scenario.params.limits_m(k) for k in kinds]
    start, end = scenario.start, scenario.end
    targets = [i for i, k in enumerate(kinds) if k in (Kind.V, Kind.H)]
    neighbours = _neighbours(points, targets, limits)
    lim_bv, lim_bh = limits[end]

    # label = [L, e, k, point, path, alive]; the heap orders by (L, k, insertion).
    first = [0.0, 0.0, 0, start, (start,), True]
    kept: dict[int, list[list]] = {start: [first]}
    heap = [(0.0, 0, 0, first)]
    pushed = 1
    best: dict[int, tuple[float, tuple[int, ...]]] = {}

    while heap:
        _, _, _, label = heapq.heappop(heap)
        length, carried, k, i, path, alive = label
        if not alive:
            continue
        # Errors on leaving i: the component i reset is 0 (both at A).
        if kinds[i] == Kind.V:
            dv, dh = 0.0, carried
        else:
            dv, dh = carried, 0.0
        d_end = math.dist(points[i], points[end])
        if dv + d_end <= lim_bv and dh + d_end <= lim_bh:
            total = length + d_end
            if k not in best or total < best[k][0]:
                best[k] = (total, (*path, end))
        visited = set(path) if elementary else ()
        for j, d in neighbours[i]:
            if j in visited:
                continue
            lim_v, lim_h = limits[j]
            if dv + d > lim_v or dh + d > lim_h:
                continue
            new_e = dh + d if kinds[j] == Kind.V else dv + d
            new = [length + d, new_e, k + 1, j, (*path, j), True]
            if _dominated(kept.setdefault(j, []), new, elementary):
                continue
            heapq.heappush(heap, (new[0], new[2], pushed, new))
            pushed += 1

    front: PlainFront = []
    for k in sorted(best):
        total, route = best[k]
        if not front or total < front[-1][0]:
            front.append((total, k, route))
    return front


def _dominated(labels: list[list], new: list, elementary: bool) -> bool:
    """Whether a kept label dominates ``new``; if not, retire the ones ``new`` dominates and
    keep ``new``."""
    length, carried, k, _, path, _ = new
    visited = set(path)
    for other in labels:
        if (
            other[0] <= length
            and other[1] <= carried
            and other[2] <= k
            and (not elementary or visited.issuperset(other[4]))
        ):
            return True
    survivors = []
    for other in labels:
        if (
            length <= other[0]
            and carried <= other[1]
            and k <= other[2]
            and (not elementary or visited.issubset(other[4]))
        ):
            other[5] = False
        else:
            survivors.append(other)
    survivors.append(new)
    labels[:] = survivors
    return False
