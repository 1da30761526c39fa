"""Compiled kernels (numba) for dense maps: the reach graph and the straight-leg layered search.

The numpy search in ``straight_layers`` materialises every candidate of a layer and sorts them
to filter dominance; on dense maps (20,000 points: 31 M arcs, over 100 M candidates) that is
most of its time and memory. Here the same search streams: each candidate is tested at once
against the labels already kept at its point (a handful on average), so nothing is
materialised. The graph is built from a uniform grid of cells one reach radius wide instead of a
KD-tree pair list.

Same model, same answers: ``straight_search.search_front`` uses these kernels for large
scenarios (the first round of the decremental relaxation, which has no critical points) and the
numpy code otherwise; the tests hold both equal to brute force and to each other.
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
    lo, side, dims, first, order = _cells(xyz, radius)
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
def _cells(
    xyz: np.ndarray, radius: float
) -> tuple[np.ndarray, float, np.ndarray, np.ndarray, np.ndarray]:
    """A uniform grid over the points: (lower corner, cell side, cells per axis, CSR start of
    each cell's points in ``order``, the points sorted by cell). Cells are at least ``radius``
    wide (``grid_arcs``: a point's neighbours within it lie in its 27 neighbouring cells)."""
    n = xyz.shape[0]
    lo = np.empty(3)
    for c in range(3):
        lo[c] = xyz[:, c].min()
    # Wider than the radius when the map spans too many radii (a few cells per point are plenty).
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
    return lo, side, dims, first, order


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
def fewest_corrections(
    xyz: np.ndarray,
    lim_v: np.ndarray,
    lim_h: np.ndarray,
    is_v: np.ndarray,
    to_end: np.ndarray,
    start: int,
    end: int,
    radius: float,
) -> tuple[int, float, np.ndarray]:
    """The fewest corrections of any feasible walk from A to B with chord legs, -1 if there is
    none, with one such walk's length and points (A first, B last).

    Walks include the simple routes and no leg model's leg is shorter than its chord, so this
    bounds every route's corrections from below. ``radius`` is at least every reach of a point
    other than B. A breadth-first search in layers of corrections over labels (point, carried
    error), straight from a grid of the points (no arc is stored): a label is kept only if it
    carries less error than every label that reached its point in the same or an earlier layer,
    so a point holds few labels over the whole search."""
    n = xyz.shape[0]
    # Cells a third of the reach wide: a label scans only the cells its reach can touch.
    lo, side, dims, first, order = _cells(xyz, radius / 3.0)
    # The search runs over the points in cell order (index q: point order[q]), so that a cell's
    # points are contiguous in memory: the scans below are most of the time.
    sx = np.empty((n, 3))
    slv = np.empty(n)
    slh = np.empty(n)
    sv = np.empty(n, np.bool_)
    ste = np.empty(n)
    r2 = np.empty(n)
    top_v = 0.0  # the largest limits of points other than A and B
    top_h = 0.0
    for q in range(n):
        p = order[q]
        sx[q] = xyz[p]
        slv[q] = lim_v[p]
        slh[q] = lim_h[p]
        sv[q] = is_v[p]
        ste[q] = to_end[p]
        r2[q] = min(lim_v[p], lim_h[p]) ** 2
        if p != start and p != end:
            top_v = max(top_v, lim_v[p])
            top_h = max(top_h, lim_h[p])
        if p == start:
            s_start = q
        if p == end:
            s_end = q
    lim_b = lim_v[end]
    cap = 1 << 16
    node = np.empty(cap, np.int64)
    es = np.empty(cap, np.float64)
    Ls = np.empty(cap, np.float64)
    parent = np.empty(cap, np.int64)
    least = np.full(n, np.inf)  # least error carried into each point so far
    slot = np.full(n, -1, np.int64)  # the point's label in the layer being made
    node[0] = s_start
    es[0] = 0.0
    Ls[0] = 0.0
    parent[0] = -1
    least[s_start] = 0.0
    size = 1
    lo_i, hi_i = 0, 1
    k = 0
    while lo_i < hi_i:
        done = -1
        done_L = np.inf
        for i in range(lo_i, hi_i):
            u = node[i]
            if es[i] + ste[u] <= lim_b and Ls[i] + ste[u] < done_L:
                done = i
                done_L = Ls[i] + ste[u]
        if done >= 0:
            hops = 1
            g = done
            while parent[g] >= 0:
                hops += 1
                g = parent[g]
            walk = np.empty(hops + 1, np.int64)
            walk[hops] = end
            g = done
            for h in range(hops - 1, -1, -1):
                walk[h] = order[node[g]]
                g = parent[g]
            return k, done_L, walk
        new_lo = size
        for i in range(lo_i, hi_i):
            u = node[i]
            dv, dh = _carried(u == s_start, sv[u], es[i])
            # A leg into j must keep both errors within j's limits, so none is longer than the
            # largest limit less the error this label carries: the cells scanned shrink with it.
            rad = min(radius, top_v - dv, top_h - dh)
            if rad < 0.0:
                continue
            ux, uy, uz = sx[u, 0], sx[u, 1], sx[u, 2]
            x0 = max(int((ux - rad - lo[0]) / side), 0)
            x1 = min(int((ux + rad - lo[0]) / side), dims[0] - 1)
            y0 = max(int((uy - rad - lo[1]) / side), 0)
            y1 = min(int((uy + rad - lo[1]) / side), dims[1] - 1)
            z0 = max(int((uz - rad - lo[2]) / side), 0)
            z1 = min(int((uz + rad - lo[2]) / side), dims[2] - 1)
            for ax in range(x0, x1 + 1):
                gx = _gap(ux, lo[0] + ax * side, side)
                for ay in range(y0, y1 + 1):
                    gy = _gap(uy, lo[1] + ay * side, side)
                    for az in range(z0, z1 + 1):
                        gz = _gap(uz, lo[2] + az * side, side)
                        if gx * gx + gy * gy + gz * gz > rad * rad:
                            continue  # the whole cell lies beyond reach
                        c = (ax * dims[1] + ay) * dims[2] + az
                        for j in range(first[c], first[c + 1]):
                            dx = ux - sx[j, 0]
                            dy = uy - sx[j, 1]
                            dz = uz - sx[j, 2]
                            d2 = dx * dx + dy * dy + dz * dz
                            # Beyond the point's reach (most of the scan), or no leg at all.
                            if d2 > r2[j] or j == u or j == s_start or j == s_end:
                                continue
                            d = np.sqrt(d2)
                            if dv + d > slv[j] or dh + d > slh[j]:
                                continue
                            ne = dh + d if sv[j] else dv + d
                            if ne >= least[j]:
                                continue
                            least[j] = ne
                            if slot[j] < new_lo:  # no label at j in this layer yet
                                if size == cap:
                                    cap *= 2
                                    node = _grow(node, cap)
                                    es = _grow(es, cap)
                                    Ls = _grow(Ls, cap)
                                    parent = _grow(parent, cap)
                                slot[j] = size
                                node[size] = j
                                size += 1
                            g = slot[j]
                            es[g] = ne
                            Ls[g] = Ls[i] + d
                            parent[g] = i
        lo_i, hi_i = new_lo, size
        k += 1
    return -1, np.inf, np.empty(0, np.int64)


@njit(cache=True)
def layered_search(
    indptr: np.ndarray,
    target: np.ndarray,
    length: np.ndarray,
    lim_v: np.ndarray,
    lim_h: np.ndarray,
    to_end: np.ndarray,
    into_end: np.ndarray,
    is_v: np.ndarray,
    start: int,
    end: int,
    kmax: int,
    bound: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, int, int]:
    """The layered label search of ``straight_layers.layered_round`` without critical points;
    labels that cannot stay below ``bound`` (inf: none known) are dropped. ``to_end`` bounds the
    length to B from each point; ``into_end`` is its arc into B (inf: none), the completion.

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
    best = bound
    f_k = np.empty(kmax + 1, np.int64)
    f_L = np.empty(kmax + 1, np.float64)
    f_label = np.empty(kmax + 1, np.int64)
    nfound = 0
    closest = start
    closest_d = to_end[start]
    k = 0
    while lo < hi and k <= kmax:
        # Completions: on to B along the arc into it (inf: none) from every label of this layer.
        layer_best = np.inf
        layer_label = -1
        for i in range(lo, hi):
            if dead[i]:
                continue
            u = node[i]
            last = into_end[u]
            if es[i] + last <= lim_b and Ls[i] + last < layer_best:
                layer_best = Ls[i] + last
                layer_label = i
            d = to_end[u]
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
            dv, dh = _carried(u == start, is_v[u], es[i])
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
def _carried(at_start: bool, is_v: bool, e: float) -> tuple[float, float]:
    """(vertical, horizontal) metres carried right after a point: none at A; after a V point
    its vertical error is reset and the horizontal one carried, and the other way round."""
    if at_start:
        return 0.0, 0.0
    if is_v:
        return 0.0, e
    return e, 0.0


@njit(cache=True)
def _gap(u: float, cell_lo: float, side: float) -> float:
    """Distance along one axis from ``u`` to the cell [cell_lo, cell_lo + side]."""
    if u < cell_lo:
        return cell_lo - u
    if u > cell_lo + side:
        return u - cell_lo - side
    return 0.0


@njit(cache=True)
def _grow(a: np.ndarray, cap: int) -> np.ndarray:
    """A copy of ``a`` with room for ``cap`` entries (the tail is zero)."""
    out = np.zeros(cap, a.dtype)
    out[: a.shape[0]] = a
    return out
