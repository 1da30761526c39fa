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
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from gcs_planner.core.diagnose import why_infeasible
from gcs_planner.core.reach import (
    ReachGraph,
    arrival_limits_m,
    bounds_are_chords,
    build_reach_graph,
    use_compiled,
)
from gcs_planner.scenario.model import Kind, Scenario


@dataclass(frozen=True)
class FrontPoint:
    length: float
    corrections: int
    points: tuple[int, ...]  # indices, A first, B last


@dataclass
class SearchStats:
    labels: int = 0  # labels kept over all rounds
    candidates: int = 0  # labels generated before filtering
    layers: int = 0
    rounds: int = 0  # decremental relaxation rounds
    critical: list[int] = field(default_factory=list)
    seconds: float = 0.0
    graph_seconds: float = 0.0
    arcs: int = 0
    # Points the search ran over: fewer than the scenario's when it was focused on the
    # ellipsoid of the fewest-corrections route (see ``_focused``).
    points: int = 0


@dataclass(frozen=True)
class FrontResult:
    front: tuple[FrontPoint, ...]
    stats: SearchStats
    # When the front is empty: the diagnosis of why (``diagnose.why_infeasible``).
    why_infeasible: str | None = None
    # The reach graph over every point, when the search made it or was given it (None when it
    # searched a focused subset only): a caller that needs it too need not build it again.
    graph: ReachGraph | None = field(default=None, repr=False, compare=False)


def straight_front(
    scenario: Scenario,
    graph: ReachGraph | None = None,
    max_corrections: int | None = None,
    compiled: bool | None = None,
    max_rounds: int | None = None,
    focus: bool | None = None,
    upper_bound: float = math.inf,
) -> FrontResult:
    """Exact Pareto front of (length, corrections) over simple feasible routes, straight legs.

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
            front, closest = _compiled_search(graph, is_v, kmax, stats, upper_bound)
        else:
            front, closest = _layered_search(graph, is_v, critical, kmax, stats, upper_bound)
        repeated = sorted(
            {p for fp in front for p in fp.points if fp.points.count(p) > 1} - set(critical)
        )
        if not repeated or stats.rounds == max_rounds:
            break
        critical.extend(repeated)
    stats.critical = critical
    stats.seconds = time.perf_counter() - t0
    why = None
    if not front:
        # A search bounded by ``upper_bound`` proves only that no route is that short.
        why = (
            why_infeasible(scenario, graph, max_corrections, simple_infeasible=True)
            if math.isinf(upper_bound)
            else f"no feasible route of at most {upper_bound:,.1f} m"
        )
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
            res = _mapped(straight_front(scenario.subset(inside), focus=False, **kw), inside)
        elif route:
            # Long thin corridors: every point lies in the ellipsoid, but the bound still
            # prunes the search. The graph over all points is made once (or was given).
            if whole is None:
                whole = build_reach_graph(scenario, compiled=True)
            res = straight_front(scenario, whole, focus=False, **kw)
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


def _inclusive(bound: float) -> float:
    """A bound on the routes' length as the searches' initial best length: a hair above it, so
    that a route as long as the bound is still found, whatever the rounding of its sum."""
    return bound * (1.0 + 1e-12) if math.isfinite(bound) else math.inf


def _compiled_search(
    graph: ReachGraph, is_v: np.ndarray, kmax: int, stats: SearchStats, bound: float
) -> tuple[list[FrontPoint], int]:
    """The first round (no critical points) by the streaming kernel of ``kernel``."""
    from gcs_planner.core.kernel import layered_search

    ks, lengths, last, node, parent, alive, layers, closest = layered_search(
        graph.indptr,
        graph.target,
        graph.length,
        graph.lim_v,
        graph.lim_h,
        graph.to_end,
        graph.into_end,
        is_v,
        graph.start,
        graph.end,
        kmax,
        _inclusive(bound),
    )
    stats.labels += int(alive)
    stats.layers += int(layers)
    front = []
    for k_, length, g in zip(ks.tolist(), lengths.tolist(), last.tolist()):
        pts = [graph.end]
        while g >= 0:
            pts.append(int(node[g]))
            g = int(parent[g])
        front.append(FrontPoint(length, k_, tuple(reversed(pts))))
    return front, int(closest)


def _layered_search(
    graph: ReachGraph,
    is_v: np.ndarray,
    critical: list[int],
    kmax: int,
    stats: SearchStats,
    bound: float,
) -> tuple[list[FrontPoint], int]:
    n = graph.n
    start, end = graph.start, graph.end
    words = (len(critical) + 63) // 64
    crit_word = np.full(n, -1, dtype=np.int64)
    crit_bit = np.zeros(n, dtype=np.uint64)
    for i, c in enumerate(critical):
        crit_word[c] = i // 64
        crit_bit[c] = np.uint64(1) << np.uint64(i % 64)
    kind_v = is_v
    lim_b = graph.lim_v[end]  # = lim_h[end] = θ/δ

    # Label store (all rounds' layers): node and parent index, for route reconstruction.
    store_node = [np.array([start], dtype=np.int64)]
    store_parent = [np.array([-1], dtype=np.int64)]
    n_stored = 1

    # Current layer.
    node = np.array([start], dtype=np.int64)
    L = np.zeros(1)
    dv = np.zeros(1)  # metres since the last vertical reset
    dh = np.zeros(1)
    mask = np.zeros((1, words), dtype=np.uint64)
    gid = np.zeros(1, dtype=np.int64)

    # Archive of kept labels for dominance: node, L, e, mask.
    arch_node, arch_L, arch_e, arch_mask = node.copy(), L.copy(), np.zeros(1), mask.copy()

    # Per point, two archived labels that dominate most candidates: the shortest (least e on a
    # tie) and the one carrying the least error (shortest on a tie). Testing candidates against
    # them is a gather per candidate, far cheaper than the full filter, which then sorts only
    # the few that survive. Labels with different critical sets are incomparable, so this is
    # used only while there are none.
    short_L = np.full(n, np.inf)
    short_e = np.full(n, np.inf)
    low_L = np.full(n, np.inf)
    low_e = np.full(n, np.inf)
    _summarise(node, L, np.zeros(1), short_L, short_e, low_L, low_e)

    best = _inclusive(bound)
    found: list[tuple[int, float, int, int]] = []  # (k, length, parent gid, end)
    closest = start
    closest_d = graph.to_end[start]

    deg = graph.degree()
    k = 0
    into_end = graph.into_end
    while len(node) and k <= kmax:
        stats.layers += 1
        # Completions: fly on to B from every label of this layer, along its arc into B (the
        # leg model may forbid one: a leg too steep for R = 0). ``to_end`` only bounds.
        last_leg = into_end[node]
        d_end = graph.to_end[node]
        ok = np.maximum(dv, dh) + last_leg <= lim_b
        if ok.any():
            total = np.where(ok, L + last_leg, np.inf)
            i = int(np.argmin(total))
            if total[i] < best:
                best = float(total[i])
                found.append((k, best, int(gid[i]), end))
        i = int(np.argmin(d_end))
        if d_end[i] < closest_d:
            closest, closest_d = int(node[i]), float(d_end[i])
        if k == kmax:
            break
        # Labels that cannot lead to a shorter route than the best with <= k corrections.
        alive = L + d_end < best
        node, L, dv, dh, mask, gid = (a[alive] for a in (node, L, dv, dh, mask, gid))
        if not len(node):
            break

        # Expand the layer over the reach graph (CSR), in chunks of labels whose arcs number
        # about CHUNK_ARCS: the candidates of a whole layer can run to hundreds of millions on
        # dense maps, and most die in the cheap filters of each chunk.
        counts = deg[node]
        if int(counts.sum()) == 0:
            break
        cum = np.cumsum(counts)
        parts = []
        lo = 0
        while lo < len(node):
            base = int(cum[lo - 1]) if lo else 0
            hi = max(lo + 1, int(np.searchsorted(cum, base + CHUNK_ARCS, side="right")))
            part = _expand(
                graph, deg, node, L, dv, dh, mask, lo, hi, best, kind_v, crit_word, crit_bit, stats
            )
            if not words:
                c_j, c_L, c_e = part[1], part[2], part[3]
                fresh = ~(
                    ((short_L[c_j] <= c_L) & (short_e[c_j] <= c_e))
                    | ((low_L[c_j] <= c_L) & (low_e[c_j] <= c_e))
                )
                part = tuple(x[fresh] for x in part)
            parts.append(part)
            lo = hi
        src, j, nL, ne, nmask, jv = (np.concatenate([pt[i] for pt in parts]) for i in range(6))
        survive = not_dominated(j, nL, ne, nmask, arch_node, arch_L, arch_e, arch_mask)
        src, j, nL, ne, nmask, jv = (a[survive] for a in (src, j, nL, ne, nmask, jv))

        new_gid = n_stored + np.arange(len(j), dtype=np.int64)
        store_node.append(j)
        store_parent.append(gid[src])
        n_stored += len(j)
        stats.labels += len(j)
        arch_node = np.concatenate([arch_node, j])
        arch_L = np.concatenate([arch_L, nL])
        arch_e = np.concatenate([arch_e, ne])
        arch_mask = np.concatenate([arch_mask, nmask])
        if not words:
            _summarise(j, nL, ne, short_L, short_e, low_L, low_e)

        node, L, mask, gid = j, nL, nmask, new_gid
        dv = np.where(jv, 0.0, ne)
        dh = np.where(jv, ne, 0.0)
        k += 1

    all_node = np.concatenate(store_node)
    all_parent = np.concatenate(store_parent)
    front = []
    for k_, length, g, last in found:
        pts = [last]
        while g >= 0:
            pts.append(int(all_node[g]))
            g = int(all_parent[g])
        front.append(FrontPoint(length, k_, tuple(reversed(pts))))
    return front, closest


CHUNK_ARCS = 1 << 22


def _expand(
    graph: ReachGraph,
    deg: np.ndarray,
    node: np.ndarray,
    L: np.ndarray,
    dv: np.ndarray,
    dh: np.ndarray,
    mask: np.ndarray,
    lo: int,
    hi: int,
    best: float,
    kind_v: np.ndarray,
    crit_word: np.ndarray,
    crit_bit: np.ndarray,
    stats: SearchStats,
) -> tuple[np.ndarray, ...]:
    """The feasible, bounded one-leg extensions of labels lo:hi of a layer, as (label index in
    the layer, point, L, carried error e, critical mask, point is V)."""
    end = graph.end
    counts = deg[node[lo:hi]]
    total_c = int(counts.sum())
    src = lo + np.repeat(np.arange(hi - lo), counts)
    offs = np.cumsum(counts) - counts
    arc = graph.indptr[node[lo:hi]][src - lo] + (np.arange(total_c) - offs[src - lo])
    j = graph.target[arc].astype(np.int64)
    d = graph.length[arc]
    nL = L[src] + d
    ndv = dv[src] + d
    ndh = dh[src] + d
    keep = (j != end) & (ndv <= graph.lim_v[j]) & (ndh <= graph.lim_h[j])
    keep &= nL + graph.to_end[j] < best
    words = mask.shape[1]
    if words:
        w = crit_word[j]
        is_crit = w >= 0
        if is_crit.any():
            wi = np.where(is_crit, w, 0)
            keep &= ~(is_crit & ((mask[src, wi] & crit_bit[j]) != 0))
    stats.candidates += int(keep.sum())
    src, j, nL, ndv, ndh = src[keep], j[keep], nL[keep], ndv[keep], ndh[keep]
    jv = kind_v[j]
    ne = np.where(jv, ndh, ndv)  # the component this point does not reset
    nmask = mask[src].copy()
    if words:
        w = crit_word[j]
        rows = np.flatnonzero(w >= 0)
        nmask[rows, w[rows]] |= crit_bit[j[rows]]
    return src, j, nL, ne, nmask, jv


def _summarise(
    j: np.ndarray,
    L: np.ndarray,
    e: np.ndarray,
    short_L: np.ndarray,
    short_e: np.ndarray,
    low_L: np.ndarray,
    low_e: np.ndarray,
) -> None:
    """Fold new labels into the per-point shortest and least-error labels (in place)."""
    if not len(j):
        return
    for first, second, key_first, key_second in (
        (L, e, short_L, short_e),
        (e, L, low_e, low_L),
    ):
        order = np.lexsort((second, first, j))
        pts, at = np.unique(j[order], return_index=True)
        f, s_ = first[order][at], second[order][at]
        better = (f < key_first[pts]) | ((f == key_first[pts]) & (s_ < key_second[pts]))
        key_first[pts[better]] = f[better]
        key_second[pts[better]] = s_[better]


def not_dominated(
    j: np.ndarray,
    L: np.ndarray,
    e: np.ndarray,
    mask: np.ndarray,
    arch_node: np.ndarray,
    arch_L: np.ndarray,
    arch_e: np.ndarray,
    arch_mask: np.ndarray,
) -> np.ndarray:
    """Which new labels no archived label and no other new label dominates (or equals).

    Labels compare only within a group (same point, same visited critical set), by
    ``staircase`` (archived labels win ties).
    """
    m = len(j)
    if m == 0:
        return np.zeros(0, dtype=bool)
    touched = np.isin(arch_node, np.unique(j))
    nodes = np.concatenate([arch_node[touched], j])
    Ls = np.concatenate([arch_L[touched], L])
    es = np.concatenate([arch_e[touched], e])
    is_new = np.concatenate([np.zeros(int(touched.sum()), dtype=bool), np.ones(m, dtype=bool)])
    if mask.shape[1]:
        masks = np.concatenate([arch_mask[touched], mask])
        key = np.column_stack([nodes.astype(np.uint64), masks])
        _, group = np.unique(key, axis=0, return_inverse=True)
        group = group.ravel().astype(np.int64)
    else:
        group = nodes
    return (staircase(group, Ls, es, is_new) & is_new)[-m:]


def staircase(
    group: np.ndarray, first: np.ndarray, second: np.ndarray, late: np.ndarray
) -> np.ndarray:
    """Which entries no other entry of their group dominates or equals on (first, second),
    smaller better; of equal entries the first not ``late`` one, else the first. Sorted by
    (group, first, second, late), an entry is kept iff its ``second`` is strictly below every
    one before it in its group. Values are replaced by their ranks so that groups can be
    offset apart with exact integer arithmetic. The mask is in the entries' order."""
    order = np.lexsort((late, second, first, group))
    _, rank = np.unique(second, return_inverse=True)
    span = int(rank.max()) + 1
    t = rank[order].astype(np.int64) - group[order].astype(np.int64) * span
    run_min = np.minimum.accumulate(t)
    prev = np.empty_like(run_min)
    prev[0] = np.iinfo(np.int64).max
    prev[1:] = run_min[:-1]
    # The first entry of a group sees the previous group's minimum, which is larger than any
    # value of this group by construction of the offsets.
    keep = np.zeros(len(order), dtype=bool)
    keep[order] = t < prev
    return keep
