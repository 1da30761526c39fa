"""Compiled kernels (numba) for dense maps: the reach graph and the straight-leg layered search.

The numpy search in ``search`` materialises every candidate of a layer and sorts them to filter
dominance; on dense maps (20,000 points: 31 M arcs, over 100 M candidates) that is most of its
time and memory. Here the same search streams: each candidate is tested at once against the
labels already kept at its point (a handful on average), so nothing is materialised. The graph
is built from a uniform grid of cells one reach radius wide instead of a KD-tree pair list.

Same model, same answers: ``search.straight_front`` uses these kernels for large scenarios (the
first round of the decremental relaxation, which has no critical points) and the numpy code
otherwise; the tests hold both equal to brute force and to each other.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def grid_arcs(
    xyz: np.ndarray, reach_to: np.ndarray, radius: float, start: int, end: int, to_end: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR arcs i -> j with |ij| <= reach_to[j], j != start, i != end, i != j: between points
    other than B through a grid of cells of side ``radius`` (>= every reach_to of a point other
    than B), and into B from the distances ``to_end``."""
    n = xyz.shape[0]
    lo = np.empty(3)
    for c in range(3):
        lo[c] = xyz[:, c].min()
    # Cells at least one radius wide, so that a point's arcs lie in its 27 neighbouring cells;
    # wider when the map spans too many radii (a few cells per point are plenty).
    span = 0.0
    for c in range(3):
        span = max(span, xyz[:, c].max() - lo[c])
    side = max(radius, 1e-9, span / 4096.0)
    dims = np.empty(3, np.int64)
    while True:
        for c in range(3):
            dims[c] = int((xyz[:, c].max() - lo[c]) / side) + 1
        if dims[0] * dims[1] * dims[2] <= max(8 * n, 4096):
            break
        side *= 2.0
    cell = np.empty(n, np.int64)
    for i in range(n):
        cx = int((xyz[i, 0] - lo[0]) / side)
        cy = int((xyz[i, 1] - lo[1]) / side)
        cz = int((xyz[i, 2] - lo[2]) / side)
        cell[i] = (cx * dims[1] + cy) * dims[2] + cz
    order = np.argsort(cell)
    ncell = dims[0] * dims[1] * dims[2]
    first = np.zeros(ncell + 1, np.int64)
    for i in range(n):
        first[cell[i] + 1] += 1
    for c in range(ncell):
        first[c + 1] += first[c]
    # Two passes over the neighbouring cells: count, then fill.
    indptr = np.zeros(n + 1, np.int64)
    _scan(xyz, reach_to, start, end, to_end, lo, side, dims, first, order, indptr[1:],
          np.empty(0, np.int32), np.empty(0, np.float64), True)  # fmt: skip
    for i in range(n):
        indptr[i + 1] += indptr[i]
    target = np.empty(indptr[n], np.int32)
    length = np.empty(indptr[n], np.float64)
    fill = indptr[:-1].copy()
    _scan(xyz, reach_to, start, end, to_end, lo, side, dims, first, order, fill, target, length,
          False)  # fmt: skip
    return indptr, target, length


@njit(cache=True)
def _scan(xyz, reach_to, start, end, to_end, lo, side, dims, first, order, slot, target, length,
          count_only):  # fmt: skip
    """One pass over every point's neighbouring cells: count arcs per source into ``slot``, or
    write them at ``slot`` (the next free place of each source) into target/length."""
    n = xyz.shape[0]
    for i in range(n):
        if i == end:
            continue
        cx = int((xyz[i, 0] - lo[0]) / side)
        cy = int((xyz[i, 1] - lo[1]) / side)
        cz = int((xyz[i, 2] - lo[2]) / side)
        for ax in range(max(cx - 1, 0), min(cx + 2, dims[0])):
            for ay in range(max(cy - 1, 0), min(cy + 2, dims[1])):
                for az in range(max(cz - 1, 0), min(cz + 2, dims[2])):
                    c = (ax * dims[1] + ay) * dims[2] + az
                    for q in range(first[c], first[c + 1]):
                        j = order[q]
                        if j == i or j == start or j == end:
                            continue
                        dx = xyz[i, 0] - xyz[j, 0]
                        dy = xyz[i, 1] - xyz[j, 1]
                        dz = xyz[i, 2] - xyz[j, 2]
                        d = np.sqrt(dx * dx + dy * dy + dz * dz)
                        if d <= reach_to[j]:
                            if count_only:
                                slot[i] += 1
                            else:
                                target[slot[i]] = j
                                length[slot[i]] = d
                                slot[i] += 1
        if to_end[i] <= reach_to[end]:
            if count_only:
                slot[i] += 1
            else:
                target[slot[i]] = end
                length[slot[i]] = to_end[i]
                slot[i] += 1


@njit(cache=True)
def layered_search(
    indptr: np.ndarray,
    target: np.ndarray,
    length: np.ndarray,
    lim_v: np.ndarray,
    lim_h: np.ndarray,
    to_end: np.ndarray,
    is_v: np.ndarray,
    start: int,
    end: int,
    kmax: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, int, int]:
    """The layered label search of ``search._layered_search`` without critical points.

    Returns, per improvement of the best complete length at layer k: (k, length, last label);
    the label store (point, parent) to rebuild routes; the labels kept, the layers searched and
    the point closest to B reached.
    """
    n = lim_v.shape[0]
    lim_b = lim_v[end]
    cap = 1 << 16
    node = np.empty(cap, np.int64)
    Ls = np.empty(cap, np.float64)
    es = np.empty(cap, np.float64)
    parent = np.empty(cap, np.int64)
    nxt = np.empty(cap, np.int64)
    dead = np.zeros(cap, np.bool_)
    head = np.full(n, -1, np.int64)
    node[0] = start
    Ls[0] = 0.0
    es[0] = 0.0
    parent[0] = -1
    nxt[0] = -1
    head[start] = 0
    size = 1
    lo, hi = 0, 1
    best = np.inf
    f_k = np.empty(kmax + 1, np.int64)
    f_L = np.empty(kmax + 1, np.float64)
    f_label = np.empty(kmax + 1, np.int64)
    nfound = 0
    closest = start
    closest_d = to_end[start]
    k = 0
    while lo < hi and k <= kmax:
        # Completions: straight on to B from every label of this layer.
        layer_best = np.inf
        layer_label = -1
        for i in range(lo, hi):
            if dead[i]:
                continue
            u = node[i]
            d = to_end[u]
            if es[i] + d <= lim_b and Ls[i] + d < layer_best:
                layer_best = Ls[i] + d
                layer_label = i
            if d < closest_d:
                closest_d = d
                closest = u
        if layer_best < best:
            best = layer_best
            f_k[nfound] = k
            f_L[nfound] = best
            f_label[nfound] = layer_label
            nfound += 1
        if k == kmax:
            break
        new_lo = size
        for i in range(lo, hi):
            if dead[i]:
                continue
            u = node[i]
            L = Ls[i]
            if L + to_end[u] >= best:
                continue
            if u == start:
                dv = 0.0
                dh = 0.0
            elif is_v[u]:
                dv = 0.0
                dh = es[i]
            else:
                dv = es[i]
                dh = 0.0
            for a in range(indptr[u], indptr[u + 1]):
                j = target[a]
                if j == end:
                    continue
                d = length[a]
                nL = L + d
                if nL + to_end[j] >= best:
                    continue
                ndv = dv + d
                ndh = dh + d
                if ndv > lim_v[j] or ndh > lim_h[j]:
                    continue
                ne = ndh if is_v[j] else ndv
                # Dominated (or equalled) by a label kept at j, from any layer <= this one?
                p = head[j]
                dominated = False
                while p >= 0:
                    if not dead[p] and Ls[p] <= nL and es[p] <= ne:
                        dominated = True
                        break
                    p = nxt[p]
                if dominated:
                    continue
                # Labels of this same layer that the new one dominates are dropped; those of
                # earlier layers stay (they have fewer corrections).
                p = head[j]
                while p >= new_lo:
                    if not dead[p] and nL <= Ls[p] and ne <= es[p]:
                        dead[p] = True
                    p = nxt[p]
                if size == cap:
                    cap *= 2
                    node = _grow(node, cap)
                    Ls = _grow(Ls, cap)
                    es = _grow(es, cap)
                    parent = _grow(parent, cap)
                    nxt = _grow(nxt, cap)
                    dead = _grow(dead, cap)
                node[size] = j
                Ls[size] = nL
                es[size] = ne
                parent[size] = i
                nxt[size] = head[j]
                head[j] = size
                size += 1
        lo, hi = new_lo, size
        k += 1
    alive = 0
    for i in range(size):
        if not dead[i]:
            alive += 1
    return (
        f_k[:nfound], f_L[:nfound], f_label[:nfound], node[:size], parent[:size], alive, k + 1,
        closest,
    )  # fmt: skip


@njit(cache=True)
def _grow(a: np.ndarray, cap: int) -> np.ndarray:
    """A copy of ``a`` with room for ``cap`` entries (the tail is zero)."""
    out = np.zeros(cap, a.dtype)
    out[: a.shape[0]] = a
    return out
