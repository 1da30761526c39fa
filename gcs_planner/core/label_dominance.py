"""Dominance between labels of the layered searches: at one point (and one set of critical
points visited), a label no longer and carrying no more error than another leaves it nothing to
reach. The straight-leg front (``straight_search``) and the cost-to-go (``cost_to_go``, on
(R, -E)) filter their layers with these."""

from __future__ import annotations

import numpy as np


def summarise(
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
