"""The compiled key table (``core.key_table_kernel``) answers as the dict it replaced: random
keys (points, masks of up to 62 bits, negative none), many repeated, the table grown from a
single slot, against a Python dict fed the same puts."""

from __future__ import annotations

import numpy as np
from numba import njit

from gcs_planner.core import key_table_kernel as kt


@njit
def _run(nodes, masks, capacity):  # noqa: ANN001, ANN202
    """Put (node, mask) -> i for each i (growing as ``keep`` does), then ask every key once
    more and a shifted one that was never put; the answers and the final table."""
    table = kt.empty_table(capacity)
    before = np.empty(len(nodes), np.int64)
    for i in range(len(nodes)):
        table = kt.with_room(table, 1)
        before[i] = kt.kept_at(table, nodes[i], masks[i])
        kt.put(table, nodes[i], masks[i], i)
    after = np.empty(len(nodes), np.int64)
    absent = np.empty(len(nodes), np.int64)
    for i in range(len(nodes)):
        after[i] = kt.kept_at(table, nodes[i], masks[i])
        absent[i] = kt.kept_at(table, nodes[i] + 100_000, masks[i])
    return before, after, absent, table


def test_the_key_table_answers_as_a_dict() -> None:
    rng = np.random.default_rng(3)
    for capacity, n, points, bits in ((1, 3000, 40, 4), (16, 5000, 400, 62), (2, 200, 3, 1)):
        nodes = rng.integers(0, points, n).astype(np.int64)
        # A few dozen masks of up to ``bits`` bits, so that keys repeat.
        pool = (rng.integers(0, 2, (30, bits)) << np.arange(bits)).sum(axis=1).astype(np.int64)
        masks = pool[rng.integers(0, len(pool), n)]
        before, after, absent, table = _run(nodes, masks, capacity)
        d: dict[tuple[int, int], int] = {}
        want_before = []
        for i, key in enumerate(zip(nodes.tolist(), masks.tolist())):
            want_before.append(d.get(key, -1))
            d[key] = i
        assert before.tolist() == want_before
        assert after.tolist() == [d[key] for key in zip(nodes.tolist(), masks.tolist())]
        assert (absent == -1).all()
        assert table.size[0] == len(d) and 2 * len(d) <= len(table.entry)
        assert any(b >= 0 for b in want_before) and any(b < 0 for b in want_before)
