"""Compiled (numba) backward layers of the cost-to-go, for dense maps and long corridors.

The numpy layers in ``cost_to_go`` materialise every (label, predecessor) candidate of a layer in
some twenty arrays, then sort the archive of every point they reach to filter dominance: tens of
millions of candidates per layer at 5,000 points, and on a 20,000-point corridor (34 layers)
minutes of sorting. Here the candidates are made one at a time, each tested at once against
the labels kept at its point, so only the survivors are ever stored: the same labels in the
same order, so the same table (tested equal to the numpy layers, table for table).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def backward_layers(
    node0: np.ndarray,
    R0: np.ndarray,
    E0: np.ndarray,
    r_ptr: np.ndarray,
    r_src: np.ndarray,
    r_len: np.ndarray,
    is_v: np.ndarray,
    lim_v: np.ndarray,
    lim_h: np.ndarray,
    own: np.ndarray,
    max_layer: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Every layer after the base one (``node0``, ``R0``, ``E0``: the labels into B, already
    Pareto-minimal) at once: (point, R, E, layer) of every label kept, the base first, then
    each layer in the order its labels are made: the labels the numpy layers of ``cost_to_go``
    keep (``_fan`` followed by ``search.not_dominated`` layer by layer).

    That filter sorts the whole archive of the layer's points each layer, which on long
    corridors (tens of layers, 20,000 points) was most of the time. Here each candidate is
    tested at once against the labels kept at its point (a per-point list, newest first): it
    is dropped if one of them has R no larger and E no smaller, and when kept it retires the
    labels of its own layer that it dominates (earlier layers' labels stay: they have fewer
    corrections)."""
    n = is_v.shape[0]
    cap = max(1024, 2 * node0.shape[0])
    node = np.empty(cap, np.int64)
    Rs = np.empty(cap)
    Es = np.empty(cap)
    layer_of = np.empty(cap, np.int64)
    nxt = np.empty(cap, np.int64)
    dead = np.zeros(cap, np.bool_)
    head = np.full(n, -1, np.int64)
    # Per point, the kept label nearest B (largest E on a tie) and the one allowing the most
    # error (nearest B on a tie): most candidates fail against one of these two at once.
    near_R = np.full(n, np.inf)
    near_e = np.full(n, np.inf)
    wide_R = np.full(n, np.inf)
    wide_e = np.full(n, np.inf)
    size = 0
    for i in range(node0.shape[0]):
        j = node0[i]
        node[size] = j
        Rs[size] = R0[i]
        Es[size] = E0[i]
        layer_of[size] = 0
        nxt[size] = head[j]
        head[j] = size
        neg = -E0[i]
        if R0[i] < near_R[j] or (R0[i] == near_R[j] and neg < near_e[j]):
            near_R[j] = R0[i]
            near_e[j] = neg
        if neg < wide_e[j] or (neg == wide_e[j] and R0[i] < wide_R[j]):
            wide_R[j] = R0[i]
            wide_e[j] = neg
        size += 1
    lo, hi = 0, size
    layer = 1
    while lo < hi and layer <= max_layer:
        for lab in range(lo, hi):
            if dead[lab]:
                continue
            j1 = node[lab]
            E1 = Es[lab]
            R1 = Rs[lab]
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
                p = head[j]
                dominated = False
                while p >= 0:
                    if not dead[p] and Rs[p] <= new_R and Es[p] >= new_E:
                        dominated = True
                        break
                    p = nxt[p]
                if dominated:
                    continue
                p = head[j]
                while p >= hi:  # this layer's labels at j (newest first)
                    if not dead[p] and new_R <= Rs[p] and new_E >= Es[p]:
                        dead[p] = True
                    p = nxt[p]
                if new_R < near_R[j] or (new_R == near_R[j] and neg < near_e[j]):
                    near_R[j] = new_R
                    near_e[j] = neg
                if neg < wide_e[j] or (neg == wide_e[j] and new_R < wide_R[j]):
                    wide_R[j] = new_R
                    wide_e[j] = neg
                if size == cap:
                    cap *= 2
                    node = _grown(node, cap)
                    Rs = _grown(Rs, cap)
                    Es = _grown(Es, cap)
                    layer_of = _grown(layer_of, cap)
                    nxt = _grown(nxt, cap)
                    dead = _grown(dead, cap)
                node[size] = j
                Rs[size] = new_R
                Es[size] = new_E
                layer_of[size] = layer
                nxt[size] = head[j]
                head[j] = size
                size += 1
        lo, hi = hi, size
        layer += 1
    alive = 0
    for i in range(size):
        if not dead[i]:
            alive += 1
    out_node = np.empty(alive, np.int64)
    out_R = np.empty(alive)
    out_E = np.empty(alive)
    out_layer = np.empty(alive, np.int64)
    k = 0
    for i in range(size):
        if not dead[i]:
            out_node[k] = node[i]
            out_R[k] = Rs[i]
            out_E[k] = Es[i]
            out_layer[k] = layer_of[i]
            k += 1
    return out_node, out_R, out_E, out_layer


@njit(cache=True)
def _grown(a: np.ndarray, cap: int) -> np.ndarray:
    """A copy of ``a`` with room for ``cap`` entries (the tail is zero)."""
    out = np.zeros(cap, a.dtype)
    out[: a.shape[0]] = a
    return out
