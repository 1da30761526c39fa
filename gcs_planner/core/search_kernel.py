"""The branch and bound's searches with dominance over walks, compiled (numba): the floors
(heading-free legs, or lb(i, j, t) over the cone of arrival headings) and the guide (airplane or
cs3d legs flown from the heading, partial routes compared as if the heading did not matter).

The same search as ``bnb._search`` with ``critical`` given, outside a probe and in its plain
order (the straight-leg search queues by least open continuation and stays in Python): the
same best-first order, the same tests in the same order, the same expansion of a partial
route as the compiled probes (``expand_kernel``), routes added to the found ones as
``_Incumbents.add`` does; what is its own is where the legs come from (``_flown_legs``) and
what it does at B. With array legs it is the Python search exactly
(tested: fronts, labels, open partial routes); with airplane or cs3d legs it flies
``airplane_kernel``'s or ``dubins_kernel``'s legs, within a few ulp of numpy's. Every 64
labels it asks the plan's budget (through ``objmode``) whether the time limit has passed and
shows progress.
"""

from __future__ import annotations

import heapq
import math

import numpy as np
from numba import objmode

from gcs_planner.core.cover_kernel import best_rows, covers, likely
from gcs_planner.core.expand_kernel import expand, new_labels, relaxed_legs
from gcs_planner.core.kernel_records import Graph, Legs, Nogoods, Pairs, Partial, Seeds, ToGo
from gcs_planner.core.key_table_kernel import empty_table
from gcs_planner.core.probability import PROB_EPS
from gcs_planner.geometry.airplane_kernel import airplane_lengths_each, free_airplane_lengths
from gcs_planner.geometry.dubins_kernel import cs_lengths
from gcs_planner.runtime.jit import inner, kernel

LEGS_ARRAYS, LEGS_PAIRS, LEGS_AIRPLANE, LEGS_CS3D = 0, 1, 2, 3
# Labels between two looks at the budget (time limit, progress).
TICK = 64

# The budget of the search running now (``tick``): objmode reaches Python objects only
# through globals.
_BUDGETS: list = []


def tick(labels: int, queued: int, found: int, bound: float) -> bool:
    """Show progress when due; whether the time limit has passed."""
    budget = _BUDGETS[-1]
    if budget.due():
        budget.report(labels, queued, found, bound)
    return budget.expired()


@inner
def _add_found(
    inc_len: list, inc_k: list, inc_p: list, inc_path: list, alive: list, L: float, k: int,
    p: float, path: np.ndarray,
) -> None:  # fmt: skip
    """``_Incumbents.add``: the found routes the new one dominates die, then it joins. (They
    are marked, not popped: ``list.pop(i)`` of a typed list of arrays corrupts the heap in
    numba 0.6x.)"""
    for i in range(len(inc_len)):
        if alive[i] and k <= inc_k[i] and p >= inc_p[i] - PROB_EPS and L <= inc_len[i]:
            alive[i] = False
    inc_len.append(L)
    inc_k.append(k)
    inc_p.append(p)
    inc_path.append(path)
    alive.append(True)


@inner
def _found_arrays(
    inc_len: list, inc_k: list, inc_p: list, alive: list
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The live found routes as arrays (lengths, corrections, probabilities) and their
    indices into the lists."""
    F = 0
    for i in range(len(alive)):
        F += alive[i]
    a_len = np.empty(F)
    a_k = np.empty(F, np.int64)
    a_p = np.empty(F)
    index = np.empty(F, np.int64)
    g = 0
    for i in range(len(alive)):
        if alive[i]:
            a_len[g], a_k[g], a_p[g], index[g] = inc_len[i], inc_k[i], inc_p[i], i
            g += 1
    return a_len, a_k, a_p, index


@inner
def _incumbent_tables(
    inc_len: list, inc_k: list, inc_p: list, alive: list, kmax: int
) -> tuple[np.ndarray, np.ndarray]:
    """The live found routes' probabilities, ascending, and ``cover_kernel.best_rows`` (as
    ``_Incumbents.best`` per number of routes at least so likely)."""
    a_len, a_k, a_p, _ = _found_arrays(inc_len, inc_k, inc_p, alive)
    # The order of np.argsort(a_p, kind="stable"), by insertion: the found routes are few, and
    # numba's merge sort costs a second of compiling.
    order = np.arange(len(a_p))
    for i in range(1, len(a_p)):
        x = order[i]
        j = i
        while j > 0 and a_p[order[j - 1]] > a_p[x]:
            order[j] = order[j - 1]
            j -= 1
        order[j] = x
    return a_p[order], best_rows(a_len, a_k, order, kmax)


@inner
def _flown_legs(
    legs: Legs, graph: Graph, pairs: Pairs, node: int, arc: int, heading: np.ndarray,
    has_heading: bool,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The legs out of ``node`` in the graph's order as the search flies them (``legs.mode``),
    and for airplane or cs3d legs the heading each ends with."""
    lo = graph.indptr[node]
    hi = graph.indptr[node + 1]
    if legs.mode != LEGS_AIRPLANE and legs.mode != LEGS_CS3D:
        return relaxed_legs(graph, pairs, node, arc), np.empty((0, 3))
    xyz = legs.xyz
    ends = np.empty((hi - lo, 3))
    for idx in range(hi - lo):
        t = graph.target[lo + idx]
        ends[idx, 0], ends[idx, 1], ends[idx, 2] = xyz[t, 0], xyz[t, 1], xyz[t, 2]
    if legs.mode == LEGS_AIRPLANE:
        # each leg on the radius and within the limits of its higher end
        m = hi - lo
        r = np.empty(m)
        tc = np.empty(m)
        td = np.empty(m)
        v = np.empty(m)
        for idx in range(m):
            t = graph.target[lo + idx]
            r[idx] = max(legs.radius_at[node], legs.radius_at[t])
            tc[idx] = min(legs.tan_climb_at[node], legs.tan_climb_at[t])
            td[idx] = min(legs.tan_descent_at[node], legs.tan_descent_at[t])
            v[idx] = max(legs.airspeed_at[node], legs.airspeed_at[t])
        if has_heading and legs.radius > 0.0:
            return airplane_lengths_each(
                xyz[node], heading, ends, r, tc, td, legs.run_in, legs.run_out, v, legs.wind
            )
        # A free heading at A, or R = 0 (the chord whatever the heading; no runs then).
        return free_airplane_lengths(xyz[node], ends, r, tc, td, legs.run_in, v, legs.wind)
    if has_heading:
        return cs_lengths(xyz[node], heading, ends, legs.radius)
    # A free heading at A: the chord (``CS3DLegs.lengths``).
    flown = np.empty(hi - lo)
    heads = np.empty((hi - lo, 3))
    for idx in range(hi - lo):
        wx = ends[idx, 0] - xyz[node, 0]
        wy = ends[idx, 1] - xyz[node, 1]
        wz = ends[idx, 2] - xyz[node, 2]
        chord = math.sqrt(wx * wx + wy * wy + wz * wz)
        flown[idx] = chord
        div = chord if chord > 0 else 1.0
        heads[idx, 0], heads[idx, 1], heads[idx, 2] = wx / div, wy / div, wz / div
    return flown, heads


@kernel
def search(
    graph: Graph,
    to_go_table: ToGo,
    pairs: Pairs,
    legs: Legs,
    seeds: Seeds,
    max_labels: int,
):  # noqa: ANN201  (see ``bnb._compiled_search``)
    """One search from A over ``graph`` (legs flown as ``legs`` says, ``pairs``' when
    ``legs.mode`` is ``LEGS_PAIRS``: ``pairs.present`` then, and only then), bounded by
    ``to_go_table``, starting with the ``seeds`` found: (labels, stopped: 0 exhausted, 1 by
    labels, 2 by time, the found routes (lengths, corrections, probabilities, points as CSR)
    and the partial routes still queued (f, L, k, mass, bounds to go as CSR))."""
    kmax = graph.kmax
    seed_len, seed_k, seed_p, seed_ptr, seed_points = seeds
    # The routes found: the seeds first.
    inc_len = [0.0]
    inc_k = [0]
    inc_p = [0.0]
    inc_path = [np.empty(0, np.int64)]
    alive = [True]
    alive.clear()
    inc_len.clear()
    inc_k.clear()
    inc_p.clear()
    inc_path.clear()
    for s in range(len(seed_len)):
        inc_len.append(seed_len[s])
        inc_k.append(seed_k[s])
        inc_p.append(seed_p[s])
        inc_path.append(seed_points[seed_ptr[s] : seed_ptr[s + 1]].copy())
        alive.append(True)
    probs_sorted, rows = _incumbent_tables(inc_len, inc_k, inc_p, alive, kmax)

    # Row 0: A, no correction yet, one error state of mass 1: (0, 0) at a mission's start.
    root = Partial(
        0.0, graph.start, np.int64(0), np.full(1, graph.start_v), np.full(1, graph.start_h),
        np.ones(1), np.int64(-1),
        np.int64(0), np.int64(0), np.array([graph.to_end_start]),
    )  # fmt: skip
    labels = new_labels(root, graph.to_end_start)
    heap = labels.heap
    heading = [legs.heading_a.copy()]  # per row: the heading it ends with, when it has one
    has_heading = [legs.has_heading_a]
    # A search keeps no nogoods (the probes' store, empty).
    no_head = empty_table(1)
    empty_i = np.empty(0, np.int64)
    empty_f = np.empty(0)
    no_nogoods = Nogoods(
        empty_i, empty_f, empty_i, empty_f, empty_i, empty_f, empty_f, empty_i, empty_i,
        empty_f, empty_f, empty_f,
    )  # fmt: skip
    count = 0
    stopped = 0
    while len(heap) > 0:
        f, _, lab = heapq.heappop(heap)
        L = labels.L[lab]
        k = labels.k[lab]
        node = labels.node[lab]
        if covers(L, k, labels.to_go[lab], rows[likely(probs_sorted, labels.mass[lab])], kmax):
            continue
        if max_labels >= 0 and count >= max_labels:
            heapq.heappush(heap, (f, np.int64(-1), lab))
            stopped = 1
            break
        if count % TICK == 0:
            queued = len(heap)
            found = 0
            for g in range(len(alive)):
                found += alive[g]
            with objmode(late="boolean"):
                late = tick(count, queued, found, f)
            if late:
                heapq.heappush(heap, (f, np.int64(-1), lab))
                stopped = 2
                break
        count += 1
        lo = graph.indptr[node]
        flown, heads = _flown_legs(
            legs, graph, pairs, node, labels.arc[lab], heading[lab], has_heading[lab]
        )
        first = np.int64(0)  # (not a literal 0: expand would compile twice)
        while True:
            before = len(labels.L)
            idx, length, arrive = expand(
                graph, to_go_table, pairs, labels, no_head, no_nogoods, lab, flown, first,
                probs_sorted, rows,
            )  # fmt: skip
            for child in range(before, len(labels.L)):  # the heading each new row ends with
                if len(heads) > 0:
                    heading.append(heads[labels.arc[child] - lo].copy())
                    has_heading.append(True)
                else:
                    heading.append(legs.heading_a)
                    has_heading.append(False)
            if idx < 0:
                break
            # At B: a route, added unless a found one dominates it.
            least = np.inf
            for g in range(len(inc_len)):
                if alive[g] and inc_k[g] <= k and inc_p[g] >= arrive - PROB_EPS:
                    least = min(least, inc_len[g])
            if not least <= length:
                points = [np.int64(graph.end)]
                back = lab
                while back >= 0:
                    points.append(labels.node[back])
                    back = labels.parent[back]
                path = np.empty(len(points), np.int64)
                for i in range(len(points)):
                    path[i] = points[len(points) - 1 - i]
                _add_found(inc_len, inc_k, inc_p, inc_path, alive, length, k, arrive, path)
                probs_sorted, rows = _incumbent_tables(inc_len, inc_k, inc_p, alive, kmax)
            first = idx + 1
    # What is left: the found routes and the partial routes still queued.
    f_len, f_k, f_p, index = _found_arrays(inc_len, inc_k, inc_p, alive)
    F = len(f_len)
    f_ptr = np.zeros(F + 1, np.int64)
    for g in range(F):
        f_ptr[g + 1] = f_ptr[g] + len(inc_path[index[g]])
    f_points = np.empty(f_ptr[F], np.int64)
    for g in range(F):
        found_path = inc_path[index[g]]
        for i in range(len(found_path)):  # (not a slice assignment: expand_kernel.new_labels)
            f_points[f_ptr[g] + i] = found_path[i]
    Q = len(heap)
    o_f = np.empty(Q)
    o_L = np.empty(Q)
    o_k = np.empty(Q, np.int64)
    o_mass = np.empty(Q)
    o_ptr = np.zeros(Q + 1, np.int64)
    for x in range(Q):
        lab = heap[x][2]
        o_f[x], o_L[x], o_k[x] = heap[x][0], labels.L[lab], labels.k[lab]
        o_mass[x] = labels.mass[lab]
        o_ptr[x + 1] = o_ptr[x] + len(labels.to_go[lab])
    o_to_go = np.empty(o_ptr[Q])
    for x in range(Q):
        bound = labels.to_go[heap[x][2]]
        for m in range(len(bound)):
            o_to_go[o_ptr[x] + m] = bound[m]
    return count, stopped, f_len, f_k, f_p, f_ptr, f_points, o_f, o_L, o_k, o_mass, o_ptr, o_to_go
