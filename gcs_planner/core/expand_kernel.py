"""The expansion of a partial route, compiled (numba), written once for the compiled probes
(``probe_kernel``) and searches (``search_kernel``): for each leg out of its point, propagate
the error states (``probability.propagate``), bound what is left (G, with pairs the larger with
G2), drop it where the found routes cover it or a kept partial route or a nogood dominates it,
and otherwise keep it and queue it. The two differ only in what they do at B (``expand``
returns there: the search adds a route, a probe escapes) and where the legs come from (the
search flies airplane or cs3d legs from the heading; ``relaxed_legs`` otherwise).

The Python reference is ``bnb._search``: the same tests in the same order, states kept in the
order they first appear (so every later sum of masses adds the same floats in the same order),
partial routes queued by (f, order of keeping).

Layout (``Labels``): a partial route is a row of lists; its error states a slice of a state
pool; its bound to go (G per further correction) an array of its own; the rows kept at a key
(point, critical points visited) linked back from ``archive[key]`` through ``next``.

numba's cache is keyed by each kernel's own source file: after editing this module (or the
cover, dominance, nogood and key-table kernels) the cached ``probe`` and ``search`` still hold
the old code until their own files change; clear the ``__pycache__/*.nbi``/``*.nbc`` files.
"""

from __future__ import annotations

import heapq
from typing import NamedTuple

import numpy as np

from gcs_planner.core.cover_kernel import covers, larger, likely, row
from gcs_planner.core.dominance_kernel import kept_dominates
from gcs_planner.core.kernel_records import Graph, Nogoods, Pairs, Partial, ToGo
from gcs_planner.core.key_table_kernel import KeyTable, empty_table, kept_at, put, with_room
from gcs_planner.runtime.jit import inner

KIND_V, KIND_H = 2, 3


class Labels(NamedTuple):
    """The partial routes of one search or probe, a row each (lists, appended by ``keep``),
    the partial routes kept per key and the queue. The fields ``dominance_kernel`` reads are
    named as the nogood store's (``kernel_records.Nogoods``)."""

    L: list  # float
    k: list  # int64
    node: list  # int64: its point
    arc: list  # int64: the arc flown last (-1: none)
    parent: list  # int64 (-1: none)
    mask: list  # int64: the critical points on its path, its own point included
    key_mask: list  # int64: its key's, those before its point
    ss: list  # int64: its first state in the pool
    sn: list  # int64: its states
    mass: list  # float: the sum of its states' masses
    vmin: list  # float: its least vertical error
    hmin: list
    to_go: list  # arrays: the bound to go per further correction
    next: list  # int64: the row kept before it at its key (-1: none)
    pool: list  # the error states: [v, h, mass] arrays, replaced when grown
    scratch: list  # [v, h, mass] arrays: the states of a leg being tried, replaced when grown
    archive: list  # [KeyTable]: key -> the last row kept there (replaced when grown)
    heap: list  # (f, order of keeping, row)


@inner
def new_labels(route: Partial, f: float) -> Labels:
    """The labels of a search or probe from ``route`` (row 0), queued with ``f``."""
    n0 = len(route.sv)
    size = max(64, 4 * n0)
    sv = np.empty(size)
    sh = np.empty(size)
    sm = np.empty(size)
    mass = 0.0
    vmin = np.inf
    hmin = np.inf
    # The states copied element by element: numba compiles a slice assignment with its
    # shape-mismatch message, string formatting that slows the first plan's compiling.
    for i in range(n0):
        sv[i] = route.sv[i]
        sh[i] = route.sh[i]
        sm[i] = route.sm[i]
        mass += route.sm[i]
        vmin = min(vmin, route.sv[i])
        hmin = min(hmin, route.sh[i])
    return Labels(
        [route.L], [route.k], [route.node], [route.arc], [np.int64(-1)], [route.mask],
        [route.mask_before], [np.int64(0)], [np.int64(n0)], [mass], [vmin], [hmin],
        [route.to_go.copy()], [np.int64(-1)], [sv, sh, sm], [np.empty(64), np.empty(64),
        np.empty(64)], [empty_table(64)],
        [(f, np.int64(-1), np.int64(0))],
    )  # fmt: skip


@inner
def grown(a: np.ndarray, need: int) -> np.ndarray:
    """``a``, or a copy with room for ``need`` (at least twice as long) when it has less."""
    if need <= len(a):
        return a
    out = np.empty(max(need, 2 * len(a)), a.dtype)
    for i in range(len(a)):  # (not a slice assignment: see new_labels)
        out[i] = a[i]
    return out


@inner
def propagate(
    sv: np.ndarray,
    sh: np.ndarray,
    sm: np.ndarray,
    s: int,
    n: int,
    leg: float,
    kind: int,
    unreliable: bool,
    p_success: float,
    residual_m: float,
    v_lim: float,
    h_lim: float,
    new_v: np.ndarray,
    new_h: np.ndarray,
    new_m: np.ndarray,
) -> int:
    """``probability.propagate`` of the states sv/sh/sm[s:s + n] over a leg into a point of
    ``kind``: the new states into new_v/new_h/new_m (room for 2n), in the order they first
    appear (so every later sum of masses adds the same floats in the same order); returns
    how many."""
    fails = unreliable and (kind == KIND_V or kind == KIND_H)
    p = p_success if fails else 1.0
    q = 1.0 - p
    count = 0
    for i in range(n):
        v = sv[s + i] + leg
        h = sh[s + i] + leg
        if not (v <= v_lim and h <= h_lim):
            continue
        w = sm[s + i]
        for branch in range(2):
            if branch == 0:
                if not p > 0.0:
                    continue
                share = w * p
                if kind == KIND_V:
                    bv, bh = 0.0, h
                elif kind == KIND_H:
                    bv, bh = v, 0.0
                else:
                    bv, bh = v, h
            else:
                if not q > 0.0:
                    continue
                share = w * q
                if kind == KIND_V:
                    bv, bh = min(v, residual_m), h
                elif kind == KIND_H:
                    bv, bh = v, min(h, residual_m)
                else:
                    bv, bh = v, h
            found = -1
            for c in range(count):
                if new_v[c] == bv and new_h[c] == bh:
                    found = c
                    break
            if found >= 0:
                new_m[found] = new_m[found] + share
            else:
                new_v[count] = bv
                new_h[count] = bh
                new_m[count] = 0.0 + share
                count += 1
    return count


@inner
def to_go_after(
    new_v: np.ndarray,
    new_h: np.ndarray,
    count: int,
    kind: int,
    j: int,
    arc: int,
    to_go: ToGo,
    pairs: Pairs,
) -> np.ndarray:
    """The bound to go per further correction of a partial route just corrected at j over
    ``arc`` (G at its least carried error, G is non-decreasing in it; with pairs the larger
    with G2), empty when no walk reaches B."""
    e_min = np.inf
    for c in range(count):
        carried = new_h[c] if kind == KIND_V else new_v[c]
        if carried < e_min:
            e_min = carried
    r = row(to_go.indptr, to_go.e_max, j, e_min)
    if r < 0:
        return np.empty(0)
    if not pairs.present:
        return to_go.table[r]
    node = pairs.node_of_arc[arc]
    if node < 0:
        return np.empty(0)
    r2 = row(pairs.to_go.indptr, pairs.to_go.e_max, node, e_min)
    if r2 < 0:
        return np.empty(0)
    return larger(to_go.table[r], pairs.to_go.table[r2])


@inner
def relaxed_legs(graph: Graph, pairs: Pairs, node: int, arc: int) -> np.ndarray:
    """The legs out of ``node`` after ``arc`` in the relaxation, in the graph's order: the
    pair relaxation's lb(i, j, t) when present (and an arc was flown), else the heading-free
    legs."""
    lo = graph.indptr[node]
    hi = graph.indptr[node + 1]
    if pairs.present and arc >= 0:
        a0 = pairs.pair_ptr[pairs.node_of_arc[arc]]
        return pairs.length[a0 : a0 + hi - lo]
    return graph.length[lo:hi]


@inner
def keep(
    labels: Labels,
    count: int,
    L: float,
    k: int,
    node: int,
    arc: int,
    parent: int,
    mask: int,
    mass: float,
    vmin: float,
    hmin: float,
    to_go: np.ndarray,
    link: int,
) -> int:
    """Keep a new partial route, its ``count`` states those in ``labels.scratch``, at the key
    (node, its parent's mask) where ``link`` was the last kept, and queue it; returns its
    row."""
    pool, scratch = labels.pool, labels.scratch
    used = labels.ss[len(labels.ss) - 1] + labels.sn[len(labels.sn) - 1]
    for x in range(3):
        if used + count > len(pool[x]):
            pool[x] = grown(pool[x], used + count)
        into, states = pool[x], scratch[x]
        for c in range(count):  # (not a slice assignment: see new_labels)
            into[used + c] = states[c]
    child = len(labels.L)
    key_mask = labels.mask[parent]
    labels.L.append(L)
    labels.k.append(k)
    labels.node.append(node)
    labels.arc.append(arc)
    labels.parent.append(parent)
    labels.mask.append(mask)
    labels.key_mask.append(key_mask)
    labels.ss.append(used)
    labels.sn.append(count)
    labels.mass.append(mass)
    labels.vmin.append(vmin)
    labels.hmin.append(hmin)
    labels.to_go.append(to_go)
    labels.next.append(link)
    archive = with_room(labels.archive[0], 1)
    labels.archive[0] = archive
    put(archive, node, key_mask, child)
    # Queued by f, then the order of keeping (that of the Python search's pushes).
    heapq.heappush(labels.heap, (L + to_go[len(to_go) - 1], np.int64(child), np.int64(child)))
    return child


@inner
def expand(
    graph: Graph,
    to_go: ToGo,
    pairs: Pairs,
    labels: Labels,
    nogood_head: KeyTable,
    nogoods: Nogoods,
    lab: int,
    legs: np.ndarray,
    first: int,
    probs_sorted: np.ndarray,
    best_rows: np.ndarray,
) -> tuple[int, float, float]:
    """Expand row ``lab`` of ``labels`` along the legs out of its point (``legs``, in the
    graph's order) from the ``first``: every partial route neither covered by the found routes
    (``probs_sorted``, ``best_rows``: ``cover_kernel``) nor dominated by one kept at its key
    or by a nogood is kept and queued. Returns at the first leg into B that can be flown: (its
    index, the route's length and probability of arriving); (-1, 0, 0) when all are done."""
    # (The fields read once: a field read in the loop costs reference counts there.)
    kmax, end, crit_bit, target = graph.kmax, graph.end, graph.crit_bit, graph.target
    lim_v, lim_h, kind, unreliable = graph.lim_v, graph.lim_h, graph.kind, graph.unreliable
    p_success, residual_m = graph.p_success, graph.residual_m
    archive = labels.archive
    lo = graph.indptr[labels.node[lab]]
    L = labels.L[lab]
    k = labels.k[lab]
    v_min = labels.vmin[lab]
    h_min = labels.hmin[lab]
    mask = labels.mask[lab]
    s = labels.ss[lab]
    n = labels.sn[lab]
    scratch = labels.scratch
    if len(scratch[0]) < 2 * n:
        for x in range(3):
            scratch[x] = np.empty(2 * n)
    new_v, new_h, new_m = scratch[0], scratch[1], scratch[2]
    pool = labels.pool
    sv, sh, sm = pool[0], pool[1], pool[2]
    for idx in range(first, len(legs)):
        j = np.int64(target[lo + idx])
        d = legs[idx]
        if not (v_min + d <= lim_v[j] and h_min + d <= lim_h[j]):
            continue
        bit = crit_bit[j]
        if bit >= 0 and (mask >> bit) & 1:
            continue
        is_end = j == end
        if not is_end and k + 1 > kmax:
            continue
        # The error-state chain (probability.propagate), states in order of appearance.
        kj = kind[j]
        count = propagate(
            sv, sh, sm, s, n, d, kj, unreliable[j], p_success, residual_m, lim_v[j], lim_h[j],
            new_v, new_h, new_m,
        )  # fmt: skip
        if count == 0:
            continue
        new_mass = 0.0
        for c in range(count):
            new_mass += new_m[c]
        nL = L + d
        if is_end:
            return idx, nL, min(1.0, new_mass)
        arc_in = lo + idx
        g = to_go_after(new_v, new_h, count, kj, j, arc_in, to_go, pairs)
        if len(g) == 0:
            continue
        if covers(nL, k + 1, g, best_rows[likely(probs_sorted, new_mass)], kmax):
            continue
        nv = np.inf
        nh = np.inf
        for c in range(count):
            nv = min(nv, new_v[c])
            nh = min(nh, new_h[c])
        # (Each dominance test is asked only where something is kept: a call with arrays
        # costs an atomic reference count per array.)
        head = kept_at(archive[0], j, mask)
        if head >= 0 and kept_dominates(
            labels, sv, sh, sm, head, nL, k + 1, new_mass, arc_in, nv, nh, new_v, new_h,
            new_m, 0, count, pairs,
        ):  # fmt: skip
            continue
        if nogood_head.size[0] > 0:
            first_ng = kept_at(nogood_head, j, mask)
            if first_ng >= 0 and kept_dominates(
                nogoods, nogoods.sv, nogoods.sh, nogoods.sm, first_ng, nL, k + 1, new_mass,
                arc_in, nv, nh, new_v, new_h, new_m, 0, count, pairs,
            ):  # fmt: skip
                continue
        keep(
            labels, count, nL, k + 1, j, arc_in, lab,
            mask | (np.int64(1) << bit) if bit >= 0 else mask, new_mass, nv, nh, g, head,
        )  # fmt: skip
        # (The pool may have grown.)
        sv, sh, sm = pool[0], pool[1], pool[2]
    return -1, 0.0, 0.0
