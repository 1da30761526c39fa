"""One round of the layered label search for the straight-leg front, over the reach graph: in
numpy (``layered_round``, with critical points no label may revisit) or by the streaming kernel
of ``kernel`` (``compiled_round``, none). ``straight_search`` runs the rounds of the
decremental relaxation and focuses them; the method is in its docstring."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from gcs_planner.core.label_dominance import not_dominated, summarise
from gcs_planner.core.reach import ReachGraph


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


def inclusive(bound: float) -> float:
    """A bound on the routes' length as the searches' initial best length: a hair above it, so
    that a route as long as the bound is still found, whatever the rounding of its sum."""
    return bound * (1.0 + 1e-12) if math.isfinite(bound) else math.inf


def compiled_round(
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
        inclusive(bound),
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


def layered_round(
    graph: ReachGraph,
    is_v: np.ndarray,
    critical: list[int],
    kmax: int,
    stats: SearchStats,
    bound: float,
) -> tuple[list[FrontPoint], int]:
    """A round of the layered search in numpy, with ``critical`` points no label may revisit
    (the decremental relaxation's); (front, the point nearest B that any label reached)."""
    n = graph.n
    start, end = graph.start, graph.end
    words, crit_word, crit_bit = _critical_bits(critical, n)
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
    summary = tuple(np.full(n, np.inf) for _ in range(4))
    short_L, short_e, low_L, low_e = summary
    summarise(node, L, np.zeros(1), short_L, short_e, low_L, low_e)

    best = inclusive(bound)
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

        layer = (node, L, dv, dh, mask)
        made = _candidates(graph, deg, layer, best, kind_v, crit_word, crit_bit, stats, summary)
        if made is None:
            break
        src, j, nL, ne, nmask, jv = made
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
            summarise(j, nL, ne, short_L, short_e, low_L, low_e)

        node, L, mask, gid = j, nL, nmask, new_gid
        dv = np.where(jv, 0.0, ne)
        dh = np.where(jv, ne, 0.0)
        k += 1

    return _routes(store_node, store_parent, found), closest


def _critical_bits(critical: list[int], n: int) -> tuple[int, np.ndarray, np.ndarray]:
    """(64-bit words per label's mask, each point's word (-1: not critical), its bit)."""
    words = (len(critical) + 63) // 64
    crit_word = np.full(n, -1, dtype=np.int64)
    crit_bit = np.zeros(n, dtype=np.uint64)
    for i, c in enumerate(critical):
        crit_word[c] = i // 64
        crit_bit[c] = np.uint64(1) << np.uint64(i % 64)
    return words, crit_word, crit_bit


def _routes(
    store_node: list[np.ndarray],
    store_parent: list[np.ndarray],
    found: list[tuple[int, float, int, int]],
) -> list[FrontPoint]:
    """The front routes, each rebuilt from its last label back through the label store."""
    all_node = np.concatenate(store_node)
    all_parent = np.concatenate(store_parent)
    front = []
    for k_, length, g, last in found:
        pts = [last]
        while g >= 0:
            pts.append(int(all_node[g]))
            g = int(all_parent[g])
        front.append(FrontPoint(length, k_, tuple(reversed(pts))))
    return front


CHUNK_ARCS = 1 << 22


def _candidates(
    graph: ReachGraph,
    deg: np.ndarray,
    layer: tuple[np.ndarray, ...],
    best: float,
    kind_v: np.ndarray,
    crit_word: np.ndarray,
    crit_bit: np.ndarray,
    stats: SearchStats,
    summary: tuple[np.ndarray, ...],
) -> tuple[np.ndarray, ...] | None:
    """The one-leg extensions of the ``layer`` (node, L, dv, dh, mask) that the cheap filters
    keep, as ``_expand`` gives them; None when no label of it has an arc out.

    The layer is expanded over the reach graph (CSR) in chunks of labels whose arcs number
    about CHUNK_ARCS: the candidates of a whole layer can run to hundreds of millions on dense
    maps, and most die in the cheap filters of each chunk (without critical points, the
    per-point shortest and least-error labels of ``summary``)."""
    node, L, dv, dh, mask = layer
    short_L, short_e, low_L, low_e = summary
    words = mask.shape[1]
    counts = deg[node]
    if int(counts.sum()) == 0:
        return None
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
    return tuple(np.concatenate([pt[i] for pt in parts]) for i in range(6))


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
