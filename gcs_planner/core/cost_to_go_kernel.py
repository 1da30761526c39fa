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
numpy layer, table for table).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def backward_fan(
    node: np.ndarray,
    R: np.ndarray,
    E: np.ndarray,
    r_ptr: np.ndarray,
    r_src: np.ndarray,
    r_len: np.ndarray,
    is_v: np.ndarray,
    lim_v: np.ndarray,
    lim_h: np.ndarray,
    own: np.ndarray,
    near_R: np.ndarray,
    near_e: np.ndarray,
    wide_R: np.ndarray,
    wide_e: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The candidates (predecessor, R, E) of one layer that pass the cheap tests, in the order
    the numpy layer makes them (labels in order, each label's reverse arcs in order). Updates
    the four summary arrays in place. ``own[j]``: the metres j's own component carries right
    after its correction."""
    cap = 1024
    out_j = np.empty(cap, np.int64)
    out_R = np.empty(cap)
    out_E = np.empty(cap)
    n_out = 0
    for lab in range(node.shape[0]):
        j1 = node[lab]
        E1 = E[lab]
        R1 = R[lab]
        for arc in range(r_ptr[j1], r_ptr[j1 + 1]):
            j = r_src[arc]
            d = r_len[arc]
            same = is_v[j] == is_v[j1]
            if is_v[j]:
                lim_own = lim_v[j1]
                lim_other = lim_h[j1]
            else:
                lim_own = lim_h[j1]
                lim_other = lim_v[j1]
            d_own = d + own[j]
            if not (d_own <= lim_own):
                continue
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
            if (near_R[j] <= new_R and near_e[j] <= neg) or (
                wide_R[j] <= new_R and wide_e[j] <= neg
            ):
                continue
            if new_R < near_R[j] or (new_R == near_R[j] and neg < near_e[j]):
                near_R[j] = new_R
                near_e[j] = neg
            if neg < wide_e[j] or (neg == wide_e[j] and new_R < wide_R[j]):
                wide_R[j] = new_R
                wide_e[j] = neg
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


@njit(cache=True)
def off_frontier(
    node: np.ndarray,
    R: np.ndarray,
    E: np.ndarray,
    f_ptr: np.ndarray,
    f_R: np.ndarray,
    f_E: np.ndarray,
) -> np.ndarray:
    """Per candidate (node, R, E): whether no frontier label of its node dominates or equals it
    (R' <= R and E' >= E). The frontier of each node is rows f_ptr[j]:f_ptr[j+1], sorted by R
    ascending, so E ascends too (a label further from B that allows no more error is off the
    frontier): the label with the largest E among those with R' <= R is the last of them,
    found by bisection. Exact comparisons, the same test as the sort of ``cost_to_go._filter``."""
    out = np.ones(node.shape[0], np.bool_)
    for c in range(node.shape[0]):
        j = node[c]
        lo = f_ptr[j]
        hi = f_ptr[j + 1]
        r = R[c]
        # First row with f_R > r.
        while lo < hi:
            mid = (lo + hi) // 2
            if f_R[mid] <= r:
                lo = mid + 1
            else:
                hi = mid
        if lo > f_ptr[j] and f_E[lo - 1] >= E[c]:
            out[c] = False
    return out


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
    indptr: np.ndarray, target: np.ndarray, length: np.ndarray, start: int, end: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The arcs between correction points (none out of A, none into B) grouped by target, as
    (r_ptr, r_src, r_len): a counting sort, in the order a stable sort by target of the arcs
    in their CSR order gives (by source, then as stored)."""
    n = indptr.shape[0] - 1
    r_ptr = np.zeros(n + 1, np.int64)
    for i in range(n):
        if i == start:
            continue
        for a in range(indptr[i], indptr[i + 1]):
            t = target[a]
            if t != end:
                r_ptr[t + 1] += 1
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
                at = fill[t]
                r_src[at] = i
                r_len[at] = length[a]
                fill[t] = at + 1
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
        if hi - lo > 1:
            seg = order[lo:hi]
            seg = seg[np.argsort(-E[seg], kind="mergesort")]
            order[lo:hi] = seg[np.argsort(R[seg], kind="mergesort")]
    return order
