"""The last entry kept per key (point, critical points visited), compiled (numba): the head of
the links back through kept partial routes (a search's or probe's archive) and through the
probes' nogoods.

A map from two int64 to one, in arrays: open addressing with linear probing, the capacity a
power of two, at most half full. It answers as a dict would (``kept_at`` is ``get(key, -1)``,
``put`` is ``d[key] = entry``); numba's typed dict costs some 3 s of compiling on the first
plan (its hashing of tuples, its string messages), this a fraction of one.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from gcs_planner.runtime.jit import inner

# Two odd multipliers below 2**63 (numba types a larger literal as uint64, and int64 times
# uint64 as a float): products wrap in int64, and the high bits are folded into the low.
_MIX_NODE = 0x27D4EB2F165667C5
_MIX_MASK = 0x165667B19E3779F9


class KeyTable(NamedTuple):
    """Slots of keys (node, mask) and their entries (-1: an empty slot); ``size[0]`` keys held."""

    node: np.ndarray  # int64
    mask: np.ndarray  # int64
    entry: np.ndarray  # int64
    size: np.ndarray  # int64, (1,)


def key_table(capacity: int = 16) -> KeyTable:
    """An empty table with ``capacity`` slots (a power of two)."""
    return KeyTable(
        np.zeros(capacity, np.int64), np.zeros(capacity, np.int64),
        np.full(capacity, -1, np.int64), np.zeros(1, np.int64),
    )  # fmt: skip


@inner
def empty_table(capacity: int) -> KeyTable:
    """``key_table`` in a kernel."""
    return KeyTable(
        np.zeros(capacity, np.int64), np.zeros(capacity, np.int64),
        np.full(capacity, -1, np.int64), np.zeros(1, np.int64),
    )  # fmt: skip


@inner
def _slot(table: KeyTable, node: int, mask: int) -> int:
    """The slot holding (node, mask), or the empty one where it would go."""
    h = np.int64(node) * _MIX_NODE + np.int64(mask) * _MIX_MASK
    h ^= h >> 31
    last = len(table.entry) - 1
    s = h & last
    while table.entry[s] >= 0 and not (table.node[s] == node and table.mask[s] == mask):
        s = (s + 1) & last
    return s


@inner
def kept_at(table: KeyTable, node: int, mask: int) -> int:
    """The last entry kept at (node, mask) (-1: none); entries link back from there."""
    return table.entry[_slot(table, node, mask)]


@inner
def put(table: KeyTable, node: int, mask: int, entry: int) -> None:
    """(node, mask) -> ``entry`` (>= 0), the table having room for one more key."""
    s = _slot(table, node, mask)
    if table.entry[s] < 0:
        table.node[s] = node
        table.mask[s] = mask
        table.size[0] += 1
    table.entry[s] = entry


@inner
def with_room(table: KeyTable, keys: int) -> KeyTable:
    """``table``, or a larger copy when ``keys`` more keys would fill more than half of it."""
    need = 2 * (table.size[0] + keys)
    capacity = len(table.entry)
    if need <= capacity:
        return table
    while capacity < need:
        capacity *= 2
    out = empty_table(capacity)
    for s in range(len(table.entry)):
        if table.entry[s] >= 0:
            put(out, table.node[s], table.mask[s], table.entry[s])
    return out
