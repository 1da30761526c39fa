"""Compiled (numba) expansion of one backward layer of the cost-to-go, for dense maps.

The numpy layer in ``cost_to_go`` materialises every (label, predecessor) candidate of a layer
in some twenty arrays before it filters them: tens of millions per layer at 5,000 points. This
makes the same candidates one at a time and keeps only those the cheap tests pass (feasible,
and dominated by neither of the two summary labels of their point), so only the survivors are
ever stored.

The summaries are updated with each survivor as it is made (the caller passes copies): a
later candidate that an earlier one of the same layer dominates or equals is dropped at once.
The full filter would drop it too (whatever dominates the earlier one dominates it), so the
labels kept after the full filter are the same; only fewer reach the sort (tested equal to the
numpy layer, table for table). For the same reason the labels can be split into slices fanned
on threads, each slice with its own copy of the summaries: a slice drops less, the filter
after drops the rest, and the table is the same whatever the number of threads.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def backward_fan(
    node: np.ndarray,
    R: np.ndarray,
    E: np.ndarray,
    first: int,
    last: int,
    r_ptr: np.ndarray,
    r_src: np.ndarray,
    r_len: np.ndarray,
    is_v: np.ndarray,
    lim_v: np.ndarray,
    lim_h: np.ndarray,
    own: np.ndarray,
    f_ptr: np.ndarray,
    f_R: np.ndarray,
    f_E: np.ndarray,
    summary: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The candidates (predecessor, R, E) that labels ``first:last`` of one layer make and
    that pass the cheap tests, labels in order. ``summary[j]`` is (near R, near -E, wide R,
    wide -E) of point j, updated in place (one row of four: the tests read all four of the
    predecessor, which is anywhere in the map, at one cache line). ``own[j]``: the metres j's
    own component carries right after its correction. A candidate the frontier of the labels
    kept so far dominates or equals (``f_ptr``, ``f_R``, ``f_E``: see ``dominated_by_frontier``)
    is dropped here too, so that only the candidates ahead of it are ever stored. Without the
    GIL: ``cost_to_go`` runs slices of the labels on threads, each with its own copy of the
    summaries (the frontier is only read)."""
    cap = 1024
    out_j = np.empty(cap, np.int64)
    out_R = np.empty(cap)
    out_E = np.empty(cap)
    n_out = 0
    for lab in range(first, last):
        j1 = node[lab]
        E1 = E[lab]
        R1 = R[lab]
        v1 = is_v[j1]
        for arc in range(r_ptr[j1], r_ptr[j1 + 1]):
            d = r_len[arc]
            # Every continuation needs d <= E1 (the carried component arrives with E1's
            # allowance at most), and the arcs come shortest first: none after this one can.
            if d > E1:
                break
            j = r_src[arc]
            vj = is_v[j]
            if vj:
                lim_own = lim_v[j1]
                lim_other = lim_h[j1]
            else:
                lim_own = lim_h[j1]
                lim_other = lim_v[j1]
            d_own = d + own[j]
            if not (d_own <= lim_own):
                continue
            same = vj == v1
            if not same and not (d_own <= E1):
                continue
            if same:
                new_E = min(lim_other, E1) - d
            else:
                new_E = lim_other - d
            if not (new_E >= 0):
                continue
            new_R = R1 + d
            neg = -new_E
            s = summary[j]
            if (s[0] <= new_R and s[1] <= neg) or (s[2] <= new_R and s[3] <= neg):
                continue
            if dominated_by_frontier(j, new_R, new_E, f_ptr, f_R, f_E):
                continue
            if new_R < s[0] or (new_R == s[0] and neg < s[1]):
                s[0] = new_R
                s[1] = neg
            if neg < s[3] or (neg == s[3] and new_R < s[2]):
                s[2] = new_R
                s[3] = neg
            if n_out == cap:
                cap *= 2
                grown_j = np.empty(cap, np.int64)
                grown_R = np.empty(cap)
                grown_E = np.empty(cap)
                grown_j[:n_out] = out_j[:n_out]
                grown_R[:n_out] = out_R[:n_out]
                grown_E[:n_out] = out_E[:n_out]
                out_j, out_R, out_E = grown_j, grown_R, grown_E
            out_j[n_out] = j
            out_R[n_out] = new_R
            out_E[n_out] = new_E
            n_out += 1
    return out_j[:n_out], out_R[:n_out], out_E[:n_out]


@njit(cache=True, nogil=True)
def dominated_by_frontier(
    j: int, r: float, e: float, f_ptr: np.ndarray, f_R: np.ndarray, f_E: np.ndarray
) -> bool:
    """Whether a frontier label of node j dominates or equals (j, r, e) (R' <= r and E' >= e).
    The frontier of each node is rows f_ptr[j]:f_ptr[j+1], sorted by R ascending, so E ascends
    too (a label further from B that allows no more error is off the frontier): the label with
    the largest E among those with R' <= r is the last of them, found by bisection. Exact
    comparisons, the same test as the sort of ``cost_to_go._filter``."""
    first = f_ptr[j]
    lo = first
    hi = f_ptr[j + 1]
    while lo < hi:  # the first row with f_R > r
        mid = (lo + hi) // 2
        if f_R[mid] <= r:
            lo = mid + 1
        else:
            hi = mid
    return lo > first and f_E[lo - 1] >= e


@njit(cache=True)
def merge_frontier(
    node: np.ndarray,
    R: np.ndarray,
    E: np.ndarray,
    order: np.ndarray,
    f_ptr: np.ndarray,
    f_R: np.ndarray,
    f_E: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rule of ``cost_to_go._filter`` by a merge instead of a sort: (which candidates are
    kept, the new frontier as rows per node sorted by R: f_ptr, node, R, E).

    ``order`` lists the candidates by (node, R ascending, E descending); the frontier of each
    node is rows f_ptr[j]:f_ptr[j+1], R ascending. Merged in the order of the sort (R
    ascending, E descending, a frontier label before a candidate equal to it), a label is on
    the new frontier iff its E exceeds every E before it at its node."""
    n = f_ptr.shape[0] - 1
    m = order.shape[0]
    keep = np.zeros(node.shape[0], np.bool_)
    cap = f_R.shape[0] + m
    g_node = np.empty(cap, np.int64)
    g_R = np.empty(cap)
    g_E = np.empty(cap)
    g_ptr = np.zeros(n + 1, np.int64)
    out = 0
    c = 0
    for j in range(n):
        g_ptr[j] = out
        a = f_ptr[j]
        a_end = f_ptr[j + 1]
        best = -np.inf
        while True:
            has_c = c < m and node[order[c]] == j
            has_a = a < a_end
            if not has_c and not has_a:
                break
            take_a = has_a
            if has_a and has_c:
                o = order[c]
                take_a = f_R[a] < R[o] or (f_R[a] == R[o] and f_E[a] >= E[o])
            if take_a:
                r = f_R[a]
                e = f_E[a]
                a += 1
                if e > best:
                    best = e
                    g_node[out] = j
                    g_R[out] = r
                    g_E[out] = e
                    out += 1
            else:
                o = order[c]
                c += 1
                if E[o] > best:
                    best = E[o]
                    keep[o] = True
                    g_node[out] = j
                    g_R[out] = R[o]
                    g_E[out] = E[o]
                    out += 1
    g_ptr[n] = out
    return keep, g_ptr, g_node[:out], g_R[:out], g_E[:out]


@njit(cache=True)
def reverse_arcs(
    indptr: np.ndarray,
    target: np.ndarray,
    length: np.ndarray,
    start: int,
    end: int,
    renumber: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The arcs between correction points (none out of A, none into B) grouped by target, as
    (r_ptr, r_src, r_len) with node i numbered ``renumber[i]``: a counting sort, then each
    target's arcs shortest first."""
    n = indptr.shape[0] - 1
    r_ptr = np.zeros(n + 1, np.int64)
    for i in range(n):
        if i == start:
            continue
        for a in range(indptr[i], indptr[i + 1]):
            t = target[a]
            if t != end:
                r_ptr[renumber[t] + 1] += 1
    for i in range(n):
        r_ptr[i + 1] += r_ptr[i]
    fill = r_ptr[:-1].copy()
    r_src = np.empty(r_ptr[n], np.int64)
    r_len = np.empty(r_ptr[n])
    for i in range(n):
        if i == start:
            continue
        for a in range(indptr[i], indptr[i + 1]):
            t = target[a]
            if t != end:
                u = renumber[t]
                at = fill[u]
                r_src[at] = renumber[i]
                r_len[at] = length[a]
                fill[u] = at + 1
    # Each target's arcs shortest first (stable, so equal lengths keep the order above):
    # ``backward_fan`` stops at the first arc longer than a label's allowance.
    for t in range(n):
        lo = r_ptr[t]
        hi = r_ptr[t + 1]
        if hi - lo > 1:
            by = np.argsort(r_len[lo:hi], kind="mergesort")
            r_src[lo:hi] = r_src[lo:hi][by]
            r_len[lo:hi] = r_len[lo:hi][by]
    return r_ptr, r_src, r_len


@njit(cache=True)
def frontier_order(node: np.ndarray, R: np.ndarray, E: np.ndarray, n: int) -> np.ndarray:
    """The candidates' indices by (node, R ascending, E descending), as ``merge_frontier``
    takes them: a counting sort by node, then each node's few candidates sorted apart (where
    a sort over all of them with three keys takes seconds). Candidates equal in all three
    come in either order: the merge keeps the first, and they are the same label."""
    m = node.shape[0]
    ptr = np.zeros(n + 1, np.int64)
    for c in range(m):
        ptr[node[c] + 1] += 1
    for i in range(n):
        ptr[i + 1] += ptr[i]
    fill = ptr[:-1].copy()
    order = np.empty(m, np.int64)
    for c in range(m):
        order[fill[node[c]]] = c
        fill[node[c]] += 1
    for j in range(n):
        lo = ptr[j]
        hi = ptr[j + 1]
        if hi - lo > 32:
            seg = order[lo:hi]
            seg = seg[np.argsort(-E[seg], kind="mergesort")]
            order[lo:hi] = seg[np.argsort(R[seg], kind="mergesort")]
        else:  # a few candidates (most points): in place, without two sorts' allocations
            for a in range(lo + 1, hi):
                c = order[a]
                b = a
                while b > lo and (
                    R[order[b - 1]] > R[c] or (R[order[b - 1]] == R[c] and E[order[b - 1]] < E[c])
                ):
                    order[b] = order[b - 1]
                    b -= 1
                order[b] = c
    return order


@njit(cache=True)
def label_table(R: np.ndarray, layer: np.ndarray, indptr: np.ndarray, layers: int) -> np.ndarray:
    """The cost-to-go table from the labels sorted by (point, E ascending): row i, column m is
    the least R over the rows i' >= i of its point with layer <= m. One pass per point from its
    last row back, carrying the running minima: the same minima as ``cost_to_go``'s numpy
    accumulate and doubling (exact: only comparisons), without a pass over the whole table
    per doubling step."""
    table = np.empty((R.shape[0], layers))
    cur = np.empty(layers)
    for j in range(indptr.shape[0] - 1):
        cur[:] = np.inf
        for i in range(indptr[j + 1] - 1, indptr[j] - 1, -1):
            r = R[i]
            for m in range(layer[i], layers):
                if r < cur[m]:
                    cur[m] = r
            table[i, :] = cur
    return table
