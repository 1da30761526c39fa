"""The exact Pareto front of (length, corrections) with straight legs.

Method: a label-setting search in layers of the number of corrections k. A label is a partial
route ending at a point, with its length L and the carried error e (metres flown since the last
reset of the component the point did *not* reset; the other one is 0 right after a correction).
Layer k+1 is made from layer k in one numpy expansion over the reach graph, then filtered:

* feasibility: the arrival limits of the target point;
* bound: L + |P - B| >= the best complete length with <= k corrections cannot lead to a
  non-dominated route (lengths only grow, corrections only grow);
* dominance at the same point: (L', e') <= (L, e) from a layer <= k+1 dominates, because a
  smaller carried error is never less feasible and the earlier layer has fewer corrections.

Routes must be simple (docs/model.md), but a label (point, L, e) does not know where it has been, so
the search above solves a relaxation over walks. Decremental state-space relaxation closes the
gap exactly: if a front walk repeats a point, that point becomes *critical*, labels carry a bit
per critical point visited, a label may not re-enter a critical point it visited, and labels
only dominate labels with the same visited set. Repeat until every front route is simple: the
front of the relaxation is then made of simple routes, and since every simple route is also a
walk, it is the front over simple routes.

This module runs the rounds (one round: ``straight_layers``) and focuses them; it finds the
front, and ``search.straight_front`` adds, when it is empty, why (``diagnose``), whose
diagnosis searches with this module in turn.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from gcs_planner.core.reach import (
    ReachGraph,
    arrival_limits_m,
    bounds_are_chords,
    build_reach_graph,
    use_compiled,
)
from gcs_planner.core.straight_layers import (
    FrontPoint,
    SearchStats,
    compiled_round,
    layered_round,
)
from gcs_planner.scenario.model import Kind, Scenario


@dataclass(frozen=True)
class FrontResult:
    front: tuple[FrontPoint, ...]
    stats: SearchStats
    # When the front is empty: why. A search bounded by ``upper_bound`` says so itself; an
    # unbounded one leaves None here for ``search.straight_front`` to diagnose
    # (``diagnose.why_infeasible``).
    why_infeasible: str | None = None
    # The reach graph over every point, when the search made it or was given it (None when it
    # searched a focused subset only): a caller that needs it too need not build it again.
    graph: ReachGraph | None = field(default=None, repr=False, compare=False)


def search_front(
    scenario: Scenario,
    graph: ReachGraph | None = None,
    max_corrections: int | None = None,
    compiled: bool | None = None,
    max_rounds: int | None = None,
    focus: bool | None = None,
    upper_bound: float = math.inf,
) -> FrontResult:
    """Exact Pareto front of (length, corrections) over simple feasible routes, straight legs;
    an empty one says why only when ``upper_bound`` bounded the search (``search.straight_front``
    diagnoses the others).

    ``compiled``: run the numba kernels (True), numpy (False), or decide by size (None).
    ``max_rounds``: stop the relaxation after this many rounds; the front may then hold walks
    that revisit points, and each of its lengths bounds the simple routes' from below.
    ``focus``: first search only the points that can lie on a front route (``_focused``) and
    fall back to all of them where that cannot be proven; None: when the kernels run and no
    ``graph`` is given (one that is must be the scenario's own reach graph to focus).
    ``upper_bound``: search only the routes no longer than this (the front returned is theirs);
    partial routes that cannot stay within it are dropped from the start.
    """
    t0 = time.perf_counter()
    compiled = use_compiled(scenario.n, compiled)
    if focus is None:
        focus = compiled and graph is None
    if focus:
        focused = _focused(scenario, max_corrections, max_rounds, graph)
        if focused is not None:
            focused.stats.seconds = time.perf_counter() - t0
            return focused
    stats = SearchStats(points=scenario.n)
    if graph is None:
        graph = build_reach_graph(scenario, compiled)
    stats.graph_seconds = time.perf_counter() - t0
    stats.arcs = len(graph.target)
    kmax = scenario.n - 2 if max_corrections is None else min(max_corrections, scenario.n - 2)
    is_v = scenario.kind == Kind.V
    critical: list[int] = []
    while True:
        stats.rounds += 1
        if compiled and not critical:
            front, closest = compiled_round(graph, is_v, kmax, stats, upper_bound)
        else:
            front, closest = layered_round(graph, is_v, critical, kmax, stats, upper_bound)
        repeated = sorted(
            {p for fp in front for p in fp.points if fp.points.count(p) > 1} - set(critical)
        )
        if not repeated or stats.rounds == max_rounds:
            break
        critical.extend(repeated)
    stats.critical = critical
    stats.seconds = time.perf_counter() - t0
    why = None
    if not front and not math.isinf(upper_bound):
        # A search bounded by ``upper_bound`` proves only that no route is that short.
        why = f"no feasible route of at most {upper_bound:,.1f} m"
    return FrontResult(tuple(front), stats, why, graph)


# Focusing: the first bound's slack over |AB|, and how much it grows while the routes within
# the bound have more corrections than the fewest any walk has.
FOCUS_SLACK = 1e-4
FOCUS_GROWTH = 2.0


def _focused(
    scenario: Scenario,
    max_corrections: int | None,
    max_rounds: int | None,
    whole: ReachGraph | None = None,
) -> FrontResult | None:
    """The front searched over the points that can lie on a front route, or None where that
    cannot be proven (the caller then searches all points).

    Every front route is at most as long as the shortest route with the fewest corrections.
    ``kernel.fewest_corrections`` finds the fewest corrections any walk has (a lower bound for
    every route). So the front of the routes no longer than a bound U is the whole front once
    it holds a route with those fewest corrections: every route longer than U has at least as
    many corrections and is longer. Bounds of growing slack over |AB| are tried until that
    holds, up to the length of the fewest-corrections walk where that walk is a route. A route
    within U only passes points p with |AP| + |PB| <= U (legs are at least their chords): an
    ellipsoid with foci A and B, which on dense maps holds a few per cent of the points (random
    20,000 points: a few hundred); elsewhere the bound prunes the search over all points."""
    from gcs_planner.core.kernel import fewest_corrections

    xyz = scenario.xyz
    start, end = scenario.start, scenario.end
    lim_v, lim_h = arrival_limits_m(scenario)
    reach_to = np.minimum(lim_v, lim_h)
    inner = reach_to[(np.arange(scenario.n) != end) & np.isfinite(reach_to)]
    if not len(inner):
        return None
    to_end = np.linalg.norm(xyz - xyz[end], axis=1)
    fewest, walk_length, walk = fewest_corrections(
        xyz, lim_v, lim_h, scenario.kind == Kind.V, to_end, start, end, float(inner.max())
    )
    kmax = scenario.n - 2 if max_corrections is None else max_corrections
    if fewest < 0 or fewest > kmax:
        return None  # no route: the whole search says why
    through = np.linalg.norm(xyz - xyz[start], axis=1) + to_end
    # A fewest-corrections walk that is a route (simple, its legs the graph's): no front route
    # is longer, so the last bound tried is its length, and that one holds the front.
    route = len(set(walk.tolist())) == len(walk) and bounds_are_chords(scenario)
    last = walk_length if route else math.inf
    ab = float(to_end[start])
    slack = FOCUS_SLACK * ab + 1.0
    labels = 0  # over every bound tried
    while True:
        bound = min(ab + slack, last)
        # The rounding slack keeps a point on the ellipsoid's surface (a straight route) inside.
        inside = np.flatnonzero(through <= bound * (1.0 + 1e-12))
        kw = {"max_corrections": max_corrections, "max_rounds": max_rounds, "upper_bound": bound}
        if 2 * len(inside) <= scenario.n:
            res = _mapped(search_front(scenario.subset(inside), focus=False, **kw), inside)
        elif route:
            # Long thin corridors: every point lies in the ellipsoid, but the bound still
            # prunes the search. The graph over all points is made once (or was given).
            if whole is None:
                whole = build_reach_graph(scenario, compiled=True)
            res = search_front(scenario, whole, focus=False, **kw)
        else:
            return None  # no faster than the whole search, and no bound known to hold
        labels += res.stats.labels
        # Proven when the search found a route with the fewest corrections no longer than the
        # bound (searched for routes within it, it finds no longer ones).
        if (res.front and res.front[0].corrections == fewest) or bound >= last:
            res.stats.labels = labels
            return res
        slack *= FOCUS_GROWTH


def _mapped(res: FrontResult, inside: np.ndarray) -> FrontResult:
    """A front searched over the points ``inside`` in the indices of the whole scenario."""
    front = tuple(
        FrontPoint(fp.length, fp.corrections, tuple(int(inside[p]) for p in fp.points))
        for fp in res.front
    )
    res.stats.critical = [int(inside[p]) for p in res.stats.critical]
    return FrontResult(front, res.stats, res.why_infeasible)
