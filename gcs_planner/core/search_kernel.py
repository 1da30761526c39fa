"""The branch and bound's searches with dominance over walks, compiled (numba): the floors
(heading-free legs, or lb(i, j, t) over the cone of arrival headings) and the guide (airplane or
cs3d legs flown from the heading, partial routes compared as if the heading did not matter).

The same search as ``bnb._search`` with ``critical`` given, outside a probe and in its plain
order (the straight-leg search queues by least open continuation and stays in Python): the
same best-first order, the same tests in the same order, the same error-state chain and
dominance as the compiled probes (``probe_kernel``, whose pieces it shares), routes added to
the found ones as ``_Incumbents.add`` does. With array legs it is the Python search exactly
(tested: fronts, labels, open partial routes); with airplane or cs3d legs it flies
``airplane_kernel``'s or ``dubins_kernel``'s legs, within a few ulp of numpy's. Every 64
labels it asks the plan's budget (through ``objmode``) whether the time limit has passed and
shows progress.
"""

from __future__ import annotations

import heapq
import math

import numpy as np
from numba import njit, objmode, types
from numba.typed import Dict

from gcs_planner.core.kernel_records import Graph, Legs, Pairs, Seeds, ToGo
from gcs_planner.core.probe_kernel import (
    _KEY,
    PROB_EPS,
    _best_rows,
    _covers,
    _first,
    _keep,
    _kept_dominates,
    _likely,
    _propagate,
    _to_go_after,
)
from gcs_planner.geometry.airplane_kernel import airplane_lengths, free_airplane_lengths
from gcs_planner.geometry.dubins_kernel import cs_lengths

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


@njit(cache=True)
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


@njit(cache=True)
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


@njit(cache=True)
def _incumbent_tables(
    inc_len: list, inc_k: list, inc_p: list, alive: list, kmax: int
) -> tuple[np.ndarray, np.ndarray]:
    """The live found routes' probabilities, ascending, and ``_best_rows`` (as
    ``_Incumbents.best`` per number of routes at least so likely)."""
    a_len, a_k, a_p, _ = _found_arrays(inc_len, inc_k, inc_p, alive)
    order = np.argsort(a_p, kind="mergesort")
    return a_p[order], _best_rows(a_len, a_k, order, kmax)


@njit(cache=True)
def search(
    graph: Graph,
    to_go_table: ToGo,
    pairs: Pairs,
    legs: Legs,
    seeds: Seeds,
    max_labels: int,
):  # noqa: ANN201  (see ``bnb._compiled_search``)
    """One search from A over ``graph`` (legs flown as ``legs`` says, ``pairs``' when
    ``legs.mode`` is ``LEGS_PAIRS``), bounded by ``to_go_table``, starting with the ``seeds``
    found: (labels, stopped: 0 exhausted, 1 by labels, 2 by time, the found routes (lengths,
    corrections, probabilities, points as CSR) and the partial routes still queued (f, L, k,
    mass, bounds to go as CSR))."""
    indptr, target, glen, lim_v, lim_h = (
        graph.indptr, graph.target, graph.length, graph.lim_v, graph.lim_h
    )  # fmt: skip
    start, end, to_end_start = graph.start, graph.end, graph.to_end_start
    kind, unreliable, crit_bit = graph.kind, graph.unreliable, graph.crit_bit
    p_success, residual_m, kmax = graph.p_success, graph.residual_m, graph.kmax
    g_ptr, g_emax, g_table = to_go_table
    node_of_arc, pair_ptr, pair_length = pairs.node_of_arc, pairs.pair_ptr, pairs.length
    p_ptr, p_emax, p_table = pairs.to_go
    legs_mode, xyz, radius, tan_climb, tan_descent = (
        legs.mode, legs.xyz, legs.radius, legs.tan_climb, legs.tan_descent
    )  # fmt: skip
    has_heading_a, heading_a = legs.has_heading_a, legs.heading_a
    run_in, run_out = legs.run_in, legs.run_out
    seed_len, seed_k, seed_p, seed_ptr, seed_points = seeds
    has_pairs = legs_mode == LEGS_PAIRS
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
    changed = True
    best_rows = np.empty((1, kmax + 1))
    probs_sorted = np.empty(0)

    lab_L = [0.0]
    lab_k = [0]
    lab_node = [np.int64(start)]
    lab_arc = [np.int64(-1)]
    lab_parent = [np.int64(-1)]
    lab_mask = [np.int64(0)]
    lab_ss = [0]
    lab_sn = [1]
    lab_mass = [1.0]
    lab_vmin = [0.0]
    lab_hmin = [0.0]
    lab_to_go = [np.array([to_end_start])]
    lab_head = [heading_a.copy()]
    lab_has_head = [has_heading_a]
    archive_next = [np.int64(-1)]
    store = (lab_L, lab_k, lab_node, lab_arc, lab_parent, lab_mask, lab_ss, lab_sn, lab_mass,
             lab_vmin, lab_hmin, lab_to_go, archive_next)  # fmt: skip
    archive = Dict.empty(key_type=_KEY, value_type=types.int64)
    sv = np.zeros(256)
    sh = np.zeros(256)
    sm = np.zeros(256)
    sm[0] = 1.0
    used = 1

    heap = [(to_end_start, np.int64(0), np.int64(0))]
    counter = 1
    labels = 0
    stopped = 0
    new_v = np.empty(64)
    new_h = np.empty(64)
    new_m = np.empty(64)
    while len(heap) > 0:
        if changed:
            probs_sorted, best_rows = _incumbent_tables(inc_len, inc_k, inc_p, alive, kmax)
            changed = False
        f, _, lab = heapq.heappop(heap)
        L = lab_L[lab]
        k = lab_k[lab]
        node = lab_node[lab]
        mass = lab_mass[lab]
        s = lab_ss[lab]
        n = lab_sn[lab]
        if _covers(L, k, lab_to_go[lab], best_rows[_likely(probs_sorted, mass)], kmax):
            continue
        if max_labels >= 0 and labels >= max_labels:
            heapq.heappush(heap, (f, np.int64(-1), lab))
            stopped = 1
            break
        if labels % TICK == 0:
            queued = len(heap)
            found = 0
            for g in range(len(alive)):
                found += alive[g]
            with objmode(late="boolean"):
                late = tick(labels, queued, found, f)
            if late:
                heapq.heappush(heap, (f, np.int64(-1), lab))
                stopped = 2
                break
        labels += 1
        lo = indptr[node]
        hi = indptr[node + 1]
        deg = hi - lo
        if legs_mode == LEGS_AIRPLANE or legs_mode == LEGS_CS3D:
            ends = np.empty((deg, 3))
            for idx in range(deg):
                t = target[lo + idx]
                ends[idx, 0], ends[idx, 1], ends[idx, 2] = xyz[t, 0], xyz[t, 1], xyz[t, 2]
        if legs_mode == LEGS_AIRPLANE:
            if lab_has_head[lab]:
                flown, heads = airplane_lengths(
                    xyz[node], lab_head[lab], ends, radius, tan_climb, tan_descent,
                    run_in, run_out,
                )  # fmt: skip
            else:
                flown, heads = free_airplane_lengths(
                    xyz[node], ends, radius, tan_climb, tan_descent, run_in
                )
        elif legs_mode == LEGS_CS3D:
            if lab_has_head[lab]:
                flown, heads = cs_lengths(xyz[node], lab_head[lab], ends, radius)
            else:  # a free heading at A: the chord (``CS3DLegs.lengths``)
                flown = np.empty(deg)
                heads = np.empty((deg, 3))
                for idx in range(deg):
                    wx = ends[idx, 0] - xyz[node, 0]
                    wy = ends[idx, 1] - xyz[node, 1]
                    wz = ends[idx, 2] - xyz[node, 2]
                    chord = math.sqrt(wx * wx + wy * wy + wz * wz)
                    flown[idx] = chord
                    div = chord if chord > 0 else 1.0
                    heads[idx, 0], heads[idx, 1], heads[idx, 2] = wx / div, wy / div, wz / div
        elif has_pairs and lab_arc[lab] >= 0:
            a0 = pair_ptr[node_of_arc[lab_arc[lab]]]
            flown = pair_length[a0 : a0 + deg]
            heads = np.empty((0, 3))
        else:
            flown = glen[lo:hi]
            heads = np.empty((0, 3))
        v_min = lab_vmin[lab]
        h_min = lab_hmin[lab]
        mask = lab_mask[lab]
        for idx in range(deg):
            j = np.int64(target[lo + idx])
            d = flown[idx]
            if not (v_min + d <= lim_v[j] and h_min + d <= lim_h[j]):
                continue
            bit = crit_bit[j]
            if bit >= 0 and (mask >> bit) & 1:
                continue
            is_end = j == end
            if not is_end and k + 1 > kmax:
                continue
            # The error-state chain (probability.propagate), states in order of appearance.
            if len(new_v) < 2 * n:
                new_v, new_h, new_m = np.empty(2 * n), np.empty(2 * n), np.empty(2 * n)
            kj = kind[j]
            count = _propagate(
                sv, sh, sm, s, n, d, kj, unreliable[j], p_success, residual_m, lim_v[j],
                lim_h[j], new_v, new_h, new_m,
            )  # fmt: skip
            if count == 0:
                continue
            new_mass = 0.0
            for c in range(count):
                new_mass += new_m[c]
            nL = L + d
            if is_end:
                arrive = min(1.0, new_mass)
                least = np.inf
                for g in range(len(inc_len)):
                    if (
                        alive[g]
                        and inc_k[g] <= k
                        and inc_p[g] >= arrive - PROB_EPS
                        and inc_len[g] < least
                    ):
                        least = inc_len[g]
                if not least <= nL:
                    points = [j]
                    back = lab
                    while back >= 0:
                        points.append(lab_node[back])
                        back = lab_parent[back]
                    path = np.empty(len(points), np.int64)
                    for i in range(len(points)):
                        path[i] = points[len(points) - 1 - i]
                    _add_found(inc_len, inc_k, inc_p, inc_path, alive, nL, k, arrive, path)
                    probs_sorted, best_rows = _incumbent_tables(
                        inc_len, inc_k, inc_p, alive, kmax
                    )
                continue
            arc_in = lo + idx
            g_to = _to_go_after(
                new_v, new_h, count, kj, j, arc_in, g_ptr, g_emax, g_table, has_pairs,
                node_of_arc, p_ptr, p_emax, p_table,
            )  # fmt: skip
            if len(g_to) == 0:
                continue
            if _covers(nL, k + 1, g_to, best_rows[_likely(probs_sorted, new_mass)], kmax):
                continue
            nv = np.inf
            nh = np.inf
            for c in range(count):
                nv = min(nv, new_v[c])
                nh = min(nh, new_h[c])
            key = (j, mask)
            head = _first(archive, key)
            if head >= 0 and _kept_dominates(  # (asked only where something is kept)
                head, archive_next, lab_L, lab_k, lab_mass, lab_arc, lab_vmin, lab_hmin,
                lab_ss, lab_sn, sv, sh, sm,
                nL, k + 1, new_mass, arc_in, nv, nh, new_v, new_h, new_m, 0, count,
                has_pairs, node_of_arc, pair_ptr, pair_length,
            ):  # fmt: skip
                continue
            child = len(lab_L)
            (sv, sh, sm), used = _keep(
                store, (sv, sh, sm), used, new_v, new_h, new_m, count, nL, k + 1, j, arc_in,
                lab, mask | (np.int64(1) << bit) if bit >= 0 else mask, new_mass, nv, nh, g_to,
                head,
            )  # fmt: skip
            if legs_mode == LEGS_AIRPLANE or legs_mode == LEGS_CS3D:
                lab_head.append(heads[idx].copy())
                lab_has_head.append(True)
            else:
                lab_head.append(heading_a)
                lab_has_head.append(False)
            archive[key] = child
            heapq.heappush(heap, (nL + g_to[len(g_to) - 1], np.int64(counter), np.int64(child)))
            counter += 1
    # What is left: the found routes and the partial routes still queued.
    f_len, f_k, f_p, index = _found_arrays(inc_len, inc_k, inc_p, alive)
    F = len(f_len)
    f_ptr = np.zeros(F + 1, np.int64)
    for g in range(F):
        f_ptr[g + 1] = f_ptr[g] + len(inc_path[index[g]])
    f_points = np.empty(f_ptr[F], np.int64)
    for g in range(F):
        f_points[f_ptr[g] : f_ptr[g + 1]] = inc_path[index[g]]
    Q = len(heap)
    o_f = np.empty(Q)
    o_L = np.empty(Q)
    o_k = np.empty(Q, np.int64)
    o_mass = np.empty(Q)
    o_ptr = np.zeros(Q + 1, np.int64)
    for x in range(Q):
        lab = heap[x][2]
        o_f[x], o_L[x], o_k[x], o_mass[x] = heap[x][0], lab_L[lab], lab_k[lab], lab_mass[lab]
        o_ptr[x + 1] = o_ptr[x] + len(lab_to_go[lab])
    o_to_go = np.empty(o_ptr[Q])
    for x in range(Q):
        o_to_go[o_ptr[x] : o_ptr[x + 1]] = lab_to_go[heap[x][2]]
    return labels, stopped, f_len, f_k, f_p, f_ptr, f_points, o_f, o_L, o_k, o_mass, o_ptr, o_to_go
