"""The probes of the branch and bound with turns (``bnb._Prober``), compiled (numba).

A probe searches the completions of one partial route in the relaxation that proved the floor
and asks whether a found route dominates every one. On dataset 2 with three objectives the
search over simple routes makes some 900 probes and 16,000 probe labels, two thirds of its time
in Python, one label at a time. The relaxation's legs come from arrays (the heading-free bounds,
or lb(i, j, t) over the cone of arrival headings), so the whole probe runs here: the same
best-first order (f, then the order of pushing), the same tests in the same order, the same
error-state chain (``probability.propagate``: states kept in the order they first appear, so
every sum of masses adds the same floats in the same order), the same dominance (Hall's
condition on the unions of the "below" sets) and the same nogoods. So it answers exactly as the
Python probe does (tested: the same fronts, labels and probe labels on random scenarios), only
faster. Two things are left out because they cannot change an answer: the whole-fan prefilter
(``prefilter.covered_fan`` drops only arcs the per-arc test drops) and the memo of the bounds
per probability level.

Layout: a partial route is a row of the label lists (``_keep``, shared with ``search_kernel``);
its error states a slice of a state pool; its bound to go (G per further correction) an array
of its own. The nogoods live across probes in arrays of the same layout (``CompiledProbes``),
linked per (point, critical points visited) through a typed dict.
"""

from __future__ import annotations

import heapq

import numpy as np
from numba import njit, types
from numba.typed import Dict

from gcs_planner.core.kernel_records import (
    NO_FAILURES,
    NO_PAIRS,
    Failures,
    Graph,
    Incumbents,
    Nogoods,
    Pairs,
    Partial,
    ToGo,
    empty_nogoods,
)
from gcs_planner.core.probability import PROB_EPS

MASS_SLACK = 1e-13  # as failure_bounds._MASS_SLACK
MAX_UNIONS = 256  # as bnb.MAX_UNIONS
KIND_V, KIND_H = 2, 3

_KEY = types.UniTuple(types.int64, 2)


def new_key_dict() -> Dict:
    """An empty (point, critical-points mask) -> first entry dict for the nogood store."""
    return Dict.empty(key_type=_KEY, value_type=types.int64)


@njit(cache=True)
def _grow_f(a: np.ndarray, need: int) -> np.ndarray:
    if need <= len(a):
        return a
    out = np.empty(max(need, 2 * len(a)), a.dtype)
    out[: len(a)] = a
    return out


@njit(cache=True)
def _row(indptr: np.ndarray, e_max: np.ndarray, j: int, e: float) -> int:
    """CostToGo._row: the first row of node j whose E is >= e, -1 when none."""
    lo = indptr[j]
    hi = indptr[j + 1]
    i = lo + np.searchsorted(e_max[lo:hi], e)
    return i if i < hi else -1


@njit(cache=True)
def _larger(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """bnb._larger: the pointwise larger of two bounds per m, each carried on with its last."""
    width = max(len(a), len(b))
    out = np.empty(width)
    for m in range(width):
        x = a[m] if m < len(a) else a[len(a) - 1]
        y = b[m] if m < len(b) else b[len(b) - 1]
        out[m] = x if x >= y else y
        if x != x or y != y:  # as numpy's maximum: nan wins
            out[m] = np.nan
    return out


@njit(cache=True)
def _best_rows(inc_len: np.ndarray, inc_k: np.ndarray, order: np.ndarray, kmax: int) -> np.ndarray:
    """_Incumbents.best per number of found routes counted (the likeliest ``c`` of them, by
    ``order``, ascending probability): row c, best[c][k] the least length with <= k
    corrections."""
    F = len(inc_len)
    rows = np.full((F + 1, kmax + 1), np.inf)
    for c in range(F + 1):
        for r in range(F - c, F):
            f = order[r]
            if inc_k[f] <= kmax and inc_len[f] < rows[c, inc_k[f]]:
                rows[c, inc_k[f]] = inc_len[f]
        for k in range(1, kmax + 1):
            if rows[c, k - 1] < rows[c, k]:
                rows[c, k] = rows[c, k - 1]
    return rows


@njit(cache=True)
def _likely(probs_sorted: np.ndarray, mass: float) -> int:
    """How many found routes are at least ``mass`` likely (within PROB_EPS)."""
    return len(probs_sorted) - np.searchsorted(probs_sorted, mass - PROB_EPS)


@njit(cache=True)
def _covers(
    length: float, k: int, to_go: np.ndarray, best: np.ndarray, kmax: int
) -> bool:
    """_Incumbents.covers with ``best`` the row for the partial route's mass."""
    m = min(len(to_go), kmax - k + 1)
    if m <= 0:
        return True
    for i in range(m):
        if not (length + to_go[i] >= best[k + i]):
            return False
    return True


@njit(cache=True)
def _dominated_end(
    inc_len: np.ndarray, inc_k: np.ndarray, inc_p: np.ndarray, length: float, k: int, p: float
) -> bool:
    """bnb._dominated: a found route with <= k corrections, at least p likely, no longer."""
    least = np.inf
    for f in range(len(inc_len)):
        if inc_k[f] <= k and inc_p[f] >= p - PROB_EPS and inc_len[f] < least:
            least = inc_len[f]
    return least <= length


@njit(cache=True)
def _margin(
    has_pairs: bool,
    node_of_arc: np.ndarray,
    pair_ptr: np.ndarray,
    pair_length: np.ndarray,
    kept: int,
    new: int,
) -> float:
    """PairBounds.margin (0 without pairs or for the same arc)."""
    if not has_pairs or kept == new:
        return 0.0
    a = pair_ptr[node_of_arc[kept]]
    b = pair_ptr[node_of_arc[new]]
    n = pair_ptr[node_of_arc[kept] + 1] - a
    m = 0.0
    for t in range(n):
        d = pair_length[a + t] - pair_length[b + t]
        if d != d:
            return 0.0  # numpy's max is nan, and max(0.0, nan) is 0.0
        if d > m:
            m = d
    return m


@njit(cache=True)
def _stochastically_dominates(
    v1: np.ndarray,
    h1: np.ndarray,
    m1: np.ndarray,
    s1: int,
    n1: int,
    shift: float,
    v2: np.ndarray,
    h2: np.ndarray,
    m2: np.ndarray,
    s2: int,
    n2: int,
) -> bool:
    """bnb._stochastically_dominates of d1 (shifted by ``shift``) over d2, slices of pools."""
    if n1 == 1:
        a = v1[s1] + shift if shift != 0.0 else v1[s1]
        b = h1[s1] + shift if shift != 0.0 else h1[s1]
        total = 0.0
        for i in range(n2):
            if not (a <= v2[s2 + i] and b <= h2[s2 + i]):
                return False
        for i in range(n2):
            total += m2[s2 + i]
        return m1[s1] >= total - PROB_EPS
    if n2 == 1:
        total = 0.0
        for i in range(n1):
            a = v1[s1 + i] + shift if shift != 0.0 else v1[s1 + i]
            b = h1[s1 + i] + shift if shift != 0.0 else h1[s1 + i]
            if a <= v2[s2] and b <= h2[s2]:
                total += m1[s1 + i]
        return total >= m2[s2] - PROB_EPS
    if n1 > 62:
        return False  # kept apart (always safe)
    below = np.empty(n2, np.int64)
    for j in range(n2):
        bits = 0
        for i in range(n1):
            a = v1[s1 + i] + shift if shift != 0.0 else v1[s1 + i]
            b = h1[s1 + i] + shift if shift != 0.0 else h1[s1 + i]
            if a <= v2[s2 + j] and b <= h2[s2 + j]:
                bits |= np.int64(1) << i
        if bits == 0:
            return False
        below[j] = bits
    unions = np.empty(MAX_UNIONS + 2, np.int64)
    unions[0] = 0
    count = 1
    for j in range(n2):
        bits = below[j]
        seen = False
        for jj in range(j):
            if below[jj] == bits:
                seen = True
                break
        if seen:
            continue
        before = count
        for u in range(before):
            new = unions[u] | bits
            dup = False
            for w in range(count):
                if unions[w] == new:
                    dup = True
                    break
            if not dup:
                if count > MAX_UNIONS:
                    return False
                unions[count] = new
                count += 1
        if count > MAX_UNIONS:
            return False
    for u in range(count):
        reach = unions[u]
        if reach == 0:
            continue
        need = 0.0
        for j in range(n2):
            if below[j] | reach == reach:
                need += m2[s2 + j]
        have = 0.0
        for i in range(n1):
            if (reach >> i) & 1:
                have += m1[s1 + i]
        if need > have + PROB_EPS:
            return False
    return True


@njit(cache=True)
def _propagate(
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


@njit(cache=True)
def _to_go_after(
    new_v: np.ndarray,
    new_h: np.ndarray,
    count: int,
    kind: int,
    j: int,
    arc: int,
    g_ptr: np.ndarray,
    g_emax: np.ndarray,
    g_table: np.ndarray,
    has_pairs: bool,
    node_of_arc: np.ndarray,
    p_ptr: np.ndarray,
    p_emax: np.ndarray,
    p_table: np.ndarray,
) -> np.ndarray:
    """The bound to go per further correction of a partial route just corrected at j over
    ``arc`` (G at its least carried error, G is non-decreasing in it; with pairs the larger
    with G2), empty when no walk reaches B."""
    e_min = np.inf
    for c in range(count):
        carried = new_h[c] if kind == KIND_V else new_v[c]
        if carried < e_min:
            e_min = carried
    r = _row(g_ptr, g_emax, j, e_min)
    if r < 0:
        return np.empty(0)
    if not has_pairs:
        return g_table[r]
    node = node_of_arc[arc]
    if node < 0:
        return np.empty(0)
    r2 = _row(p_ptr, p_emax, node, e_min)
    if r2 < 0:
        return np.empty(0)
    return _larger(g_table[r], p_table[r2])


@njit(cache=True)
def _dominates(
    aL: float,
    ak: int,
    am: float,
    a_arc: int,
    av: float,
    ah: float,
    a_sv: np.ndarray,
    a_sh: np.ndarray,
    a_sm: np.ndarray,
    a_s: int,
    a_n: int,
    L: float,
    k: int,
    mass: float,
    arc: int,
    v: float,
    h: float,
    sv: np.ndarray,
    sh: np.ndarray,
    sm: np.ndarray,
    s: int,
    n: int,
    has_pairs: bool,
    node_of_arc: np.ndarray,
    pair_ptr: np.ndarray,
    pair_length: np.ndarray,
) -> bool:
    """One kept partial route against a new one (bnb._dominated_by's loop body), once the
    scalars allow it (``_kept_dominates`` tests them first)."""
    shift = _margin(has_pairs, node_of_arc, pair_ptr, pair_length, a_arc, arc)
    return (
        aL + shift <= L
        and av + shift <= v
        and ah + shift <= h
        and _stochastically_dominates(a_sv, a_sh, a_sm, a_s, a_n, shift, sv, sh, sm, s, n)
    )


@njit(cache=True)
def _forced(weight: float, gap: float, failures: int, q_fail: float) -> int:
    """FailureBounds.forced: the first failures a state of mass ``weight`` must survive in a
    continuation that loses less than ``gap`` (-1: none, the state may die whole)."""
    if weight < gap + MASS_SLACK:
        return -1
    q = 0
    while q < failures and weight * q_fail ** float(q + 1) >= gap + MASS_SLACK:
        q += 1
    return q


@njit(cache=True)
def _first(links: Dict, key: tuple) -> int:
    """The last entry kept at ``key`` (-1: none); entries link back from there."""
    if key in links:
        return links[key]
    return -1


@njit(cache=True)
def _kept_dominates(
    first: int,
    nxt,  # noqa: ANN001 (list or array: the entries' links)
    kL,  # noqa: ANN001
    kk,  # noqa: ANN001
    kmass,  # noqa: ANN001
    karc,  # noqa: ANN001
    kvmin,  # noqa: ANN001
    khmin,  # noqa: ANN001
    kss,  # noqa: ANN001
    ksn,  # noqa: ANN001
    pool_v: np.ndarray,
    pool_h: np.ndarray,
    pool_m: np.ndarray,
    L: float,
    k: int,
    mass: float,
    arc: int,
    v: float,
    h: float,
    sv: np.ndarray,
    sh: np.ndarray,
    sm: np.ndarray,
    s: int,
    n: int,
    has_pairs: bool,
    node_of_arc: np.ndarray,
    pair_ptr: np.ndarray,
    pair_length: np.ndarray,
) -> bool:
    """Whether one of the kept partial routes linked from ``first`` (a search's archive at one
    key, or the nogoods there) dominates the new one (``bnb._dominated_by``)."""
    e = first
    while e >= 0:
        # The scalars first, here: most kept routes fail them, and a call with the arrays
        # costs an atomic reference count per array and call (numba does not inline it).
        if (
            kL[e] <= L and kk[e] <= k and kmass[e] >= mass - PROB_EPS and kvmin[e] <= v
            and khmin[e] <= h
        ) and _dominates(
            kL[e], kk[e], kmass[e], karc[e], kvmin[e], khmin[e], pool_v, pool_h, pool_m,
            kss[e], ksn[e], L, k, mass, arc, v, h, sv, sh, sm, s, n,
            has_pairs, node_of_arc, pair_ptr, pair_length,
        ):  # fmt: skip
            return True
        e = nxt[e]
    return False


@njit(cache=True)
def _failure_rows(
    f_ptr: np.ndarray,
    f_emax: np.ndarray,
    f_table: np.ndarray,
    f_n: int,
    f_failures: int,
    f_qfail: float,
    f_isv: np.ndarray,
    at: int,
    sv: np.ndarray,
    sh: np.ndarray,
    sm: np.ndarray,
    s: int,
    n: int,
    gap: float,
) -> np.ndarray:
    """FailureBounds.bound (an empty array for None)."""
    carried_h = f_isv[at]  # a V point resets v: h is carried, and vice versa
    e_min = np.inf
    for i in range(n):
        e = sh[s + i] if carried_h else sv[s + i]
        if e < e_min:
            e_min = e
    r = _row(f_ptr, f_emax, at, e_min)
    if r < 0:
        return np.empty(0)
    out = f_table[r].copy()
    for i in range(n):
        q = _forced(sm[s + i], gap, f_failures, f_qfail)
        if q < 0:
            continue
        e = sh[s + i] if carried_h else sv[s + i]
        r = _row(f_ptr, f_emax, q * f_n + at, e)
        if r < 0:
            return np.empty(0)
        row = f_table[r]
        for m in range(len(out)):
            if row[m] > out[m] or row[m] != row[m]:
                out[m] = row[m]
    return out


@njit(cache=True)
def _level_tables(
    levels: np.ndarray,
    probs_sorted: np.ndarray,
    best_rows: np.ndarray,
    has_ceil: bool,
    ceil_rows: np.ndarray,
    kmax: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Per probability interval i (above the likeliest found route, then below each level):
    the found routes' best[c] that match it (inf for the first), and next_bad[c], the first
    c' >= c where the ceiling is below that best (kmax + 1: none; without a ceiling every
    c'). Both best and the ceiling are non-increasing in c, and so is every bound to go, so
    past the end of a bound (constant from there) ``_covers_by_level`` needs only these."""
    nlev = len(levels)
    level_best = np.full((nlev + 1, kmax + 1), np.inf)
    next_bad = np.empty((nlev + 1, kmax + 2), np.int64)
    for i in range(nlev + 1):
        if i > 0:
            level_best[i] = best_rows[_likely(probs_sorted, levels[i - 1])]
        next_bad[i, kmax + 1] = kmax + 1
        for c in range(kmax, -1, -1):
            bad = not has_ceil or ceil_rows[i, c] < level_best[i, c]
            next_bad[i, c] = c if bad else next_bad[i, c + 1]
    return level_best, next_bad


@njit(cache=True)
def _covers_by_level(
    length: float,
    k: int,
    mass: float,
    to_go: np.ndarray,
    kmax: int,
    levels: np.ndarray,
    level_best: np.ndarray,
    next_bad: np.ndarray,
    has_ceil: bool,
    ceil_rows: np.ndarray,
    has_fail: bool,
    f_ptr: np.ndarray,
    f_emax: np.ndarray,
    f_table: np.ndarray,
    f_n: int,
    f_failures: int,
    f_qfail: float,
    f_isv: np.ndarray,
    at: int,
    sv: np.ndarray,
    sh: np.ndarray,
    sm: np.ndarray,
    s: int,
    n: int,
) -> bool:
    """_Incumbents.covers_by_level with the probe's bound per level (bnb._search.by_level):
    for each probability interval, every m with max(L + bound(m), ceiling) >= best. Checked
    entry by entry over the bound's own length, and past it (where L + bound is a constant A)
    at once: it fails there iff some c has A < best[c] (c below the first best <= A) and the
    ceiling below best[c] (``_level_tables``)."""
    width = kmax - k + 1
    if width <= 0:
        return True
    nlev = len(levels)
    # The bound depends on the gap only through the failures each state must survive: levels
    # that force the same ones share it (as bnb's memo per forced tuple).
    forced = np.full(n, -2, np.int64)
    bound = to_go
    for i in range(nlev + 1):
        floor = levels[i] + PROB_EPS if i < nlev else 0.0
        if floor >= mass:
            continue
        if has_fail:
            same = forced[0] != -2
            for x in range(n):
                q = _forced(sm[s + x], mass - floor, f_failures, f_qfail)
                if q != forced[x]:
                    same = False
                    forced[x] = q
            if not same:
                rows = _failure_rows(
                    f_ptr, f_emax, f_table, f_n, f_failures, f_qfail, f_isv, at, sv, sh, sm,
                    s, n, mass - floor,
                )  # fmt: skip
                bound = rows if len(rows) == 0 else _larger(rows, to_go)
            if len(bound) == 0:
                continue
        best = level_best[i]
        m = min(len(bound), width)
        for c in range(m):
            reach = length + bound[c]
            if has_ceil and ceil_rows[i, k + c] > reach:
                reach = ceil_rows[i, k + c]
            if not (reach >= best[k + c]):
                return False
        if m < width:
            A = length + bound[len(bound) - 1]
            lo = k + m
            hi = kmax + 1
            while lo < hi:  # the first c >= k + m with best[c] <= A
                mid = (lo + hi) // 2
                if best[mid] <= A:
                    hi = mid
                else:
                    lo = mid + 1
            if next_bad[i, k + m] < lo:
                return False
    return True


@njit(cache=True)
def _keep(
    store: tuple,
    pool: tuple,
    used: int,
    new_v: np.ndarray,
    new_h: np.ndarray,
    new_m: np.ndarray,
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
) -> tuple[tuple, int]:
    """Keep a new partial route: its row in ``store`` (the lists L, k, point, arc flown last,
    parent, critical points on its path, first state, states, mass, least v, least h, bound to
    go, next kept at its key) and its error states at ``used`` in ``pool`` (v, h, mass arrays,
    grown when full). Returns the pool and how much of it is used."""
    lab_L, lab_k, lab_node, lab_arc, lab_parent, lab_mask, lab_ss, lab_sn = store[:8]
    lab_mass, lab_vmin, lab_hmin, lab_to_go, links = store[8:]
    sv, sh, sm = pool
    if used + count > len(sv):
        sv = _grow_f(sv, used + count)
        sh = _grow_f(sh, used + count)
        sm = _grow_f(sm, used + count)
    sv[used : used + count] = new_v[:count]
    sh[used : used + count] = new_h[:count]
    sm[used : used + count] = new_m[:count]
    lab_ss.append(used)
    lab_sn.append(count)
    lab_L.append(L)
    lab_k.append(k)
    lab_node.append(node)
    lab_arc.append(arc)
    lab_parent.append(parent)
    lab_mask.append(mask)
    lab_mass.append(mass)
    lab_vmin.append(vmin)
    lab_hmin.append(hmin)
    lab_to_go.append(to_go)
    links.append(link)
    return (sv, sh, sm), used + count


@njit(cache=True)
def probe(
    graph: Graph,
    to_go_table: ToGo,
    pairs: Pairs,
    failures: Failures,
    found: Incumbents,
    route: Partial,
    nogood_head: Dict,
    nogoods: Nogoods,
    max_labels: int,
):  # noqa: ANN201  (a tuple of many arrays; see the Python side, ``CompiledProbes``)
    """One probe of ``route`` in the relaxation (``graph``'s legs, or ``pairs``' when present,
    bounded by ``to_go_table``, ``failures`` and the ceiling of ``found``): (covered, labels,
    the escaping completion's points after the partial route, and, when covered, the partial
    routes it expanded: their keys, scalars and states, to join the ``nogoods``)."""
    indptr, target, glen, lim_v, lim_h = (
        graph.indptr, graph.target, graph.length, graph.lim_v, graph.lim_h
    )  # fmt: skip
    end, kind, unreliable, crit_bit = graph.end, graph.kind, graph.unreliable, graph.crit_bit
    p_success, residual_m, kmax = graph.p_success, graph.residual_m, graph.kmax
    g_ptr, g_emax, g_table = to_go_table
    has_pairs, node_of_arc, pair_ptr, pair_length = (
        pairs.present, pairs.node_of_arc, pairs.pair_ptr, pairs.length
    )  # fmt: skip
    p_ptr, p_emax, p_table = pairs.to_go
    has_fail, f_n, f_failures, f_qfail, f_isv = (
        failures.present, failures.n, failures.failures, failures.q_fail, failures.is_v
    )  # fmt: skip
    f_ptr, f_emax, f_table = failures.to_go
    has_ceil, ceil_rows, inc_len, inc_k, inc_p = (
        found.has_ceiling, found.ceiling_rows, found.length, found.k, found.p
    )  # fmt: skip
    probs_sorted, order, levels = found.probs_sorted, found.order, found.levels
    o_L, o_node, o_k, o_sv, o_sh, o_sm = route.L, route.node, route.k, route.sv, route.sh, route.sm
    o_arc, o_mask_before, o_mask, o_to_go = route.arc, route.mask_before, route.mask, route.to_go
    best_rows = _best_rows(inc_len, inc_k, order, kmax)
    level_best, next_bad = _level_tables(levels, probs_sorted, best_rows, has_ceil, ceil_rows, kmax)
    # Labels: the partial route probed is label 0.
    lab_L = [o_L]
    lab_k = [o_k]
    lab_node = [o_node]
    lab_arc = [o_arc]
    lab_parent = [-1]
    lab_mask = [o_mask]  # critical points on its path, its own point included
    lab_kmask = [o_mask_before]  # its key's: those before its point
    n0 = len(o_sv)
    sv = np.empty(max(64, 4 * n0))
    sh = np.empty(len(sv))
    sm = np.empty(len(sv))
    sv[:n0] = o_sv
    sh[:n0] = o_sh
    sm[:n0] = o_sm
    used = n0
    lab_ss = [0]
    lab_sn = [n0]
    mass0 = 0.0
    v0 = np.inf
    h0 = np.inf
    for i in range(n0):
        mass0 += o_sm[i]
        v0 = min(v0, o_sv[i])
        h0 = min(h0, o_sh[i])
    lab_mass = [mass0]
    lab_vmin = [v0]
    lab_hmin = [h0]
    lab_to_go = [o_to_go.copy()]
    archive_next = [-1]
    store = (lab_L, lab_k, lab_node, lab_arc, lab_parent, lab_mask, lab_ss, lab_sn, lab_mass,
             lab_vmin, lab_hmin, lab_to_go, archive_next)  # fmt: skip
    archive = Dict.empty(key_type=_KEY, value_type=types.int64)
    empty_i = np.empty(0, np.int64)
    empty_f = np.empty(0)
    # No nogoods to add: (node, mask, L, k, mass, arc, vmin, hmin, start, count, v, h, m).
    nothing = (empty_i, empty_i, empty_f, empty_i, empty_f, empty_i, empty_f, empty_f,
               empty_i, empty_i, empty_f, empty_f, empty_f)  # fmt: skip

    # The partial route itself may be covered by a nogood already. (Each call is asked only
    # where something is kept: a call with arrays costs an atomic reference count per array,
    # which numba does not prune from a function with loops and early returns.)
    first_ng = _first(nogood_head, (o_node, o_mask_before))
    if first_ng >= 0 and _kept_dominates(
        first_ng, nogoods.next, nogoods.L, nogoods.k, nogoods.mass, nogoods.arc,
        nogoods.vmin, nogoods.hmin, nogoods.ss, nogoods.sn, nogoods.sv, nogoods.sh, nogoods.sm,
        o_L, o_k, mass0, o_arc, v0, h0, sv, sh, sm, 0, n0,
        has_pairs, node_of_arc, pair_ptr, pair_length,
    ):  # fmt: skip
        return (True, 0, empty_i, *nothing)

    # (f, order of pushing, label); alone in the queue, the partial route's f is moot.
    heap = [(o_L, np.int64(-1), np.int64(0))]
    counter = 0
    labels = 0
    exhausted = True
    escape = -1
    escape_to = -1
    expanded = [np.int64(0)]
    expanded.pop()
    new_v = np.empty(64)
    new_h = np.empty(64)
    new_m = np.empty(64)
    while len(heap) > 0:
        _, _, lab = heapq.heappop(heap)
        L = lab_L[lab]
        k = lab_k[lab]
        node = lab_node[lab]
        mass = lab_mass[lab]
        s = lab_ss[lab]
        n = lab_sn[lab]
        to_go = lab_to_go[lab]
        best = best_rows[_likely(probs_sorted, mass)]
        if _covers(L, k, to_go, best, kmax):
            continue
        if has_fail or has_ceil:
            if _covers_by_level(
                L, k, mass, to_go, kmax, levels, level_best, next_bad, has_ceil, ceil_rows,
                has_fail, f_ptr, f_emax, f_table, f_n, f_failures, f_qfail, f_isv, node,
                sv, sh, sm, s, n,
            ):  # fmt: skip
                continue
        if labels >= max_labels:
            exhausted = False
            break
        labels += 1
        expanded.append(lab)
        lo = indptr[node]
        hi = indptr[node + 1]
        if has_pairs:
            legs_at = pair_ptr[node_of_arc[lab_arc[lab]]]
        v_min = lab_vmin[lab]
        h_min = lab_hmin[lab]
        mask = lab_mask[lab]
        for idx in range(hi - lo):
            j = np.int64(target[lo + idx])
            d = pair_length[legs_at + idx] if has_pairs else glen[lo + idx]
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
                if not _dominated_end(inc_len, inc_k, inc_p, nL, k, min(1.0, new_mass)):
                    escape = lab
                    escape_to = j
                    break
                continue
            arc_in = lo + idx
            g = _to_go_after(
                new_v, new_h, count, kj, j, arc_in, g_ptr, g_emax, g_table, has_pairs,
                node_of_arc, p_ptr, p_emax, p_table,
            )  # fmt: skip
            if len(g) == 0:
                continue
            if _covers(nL, k + 1, g, best_rows[_likely(probs_sorted, new_mass)], kmax):
                continue
            nv = np.inf
            nh = np.inf
            for c in range(count):
                nv = min(nv, new_v[c])
                nh = min(nh, new_h[c])
            key = (j, mask)
            head = _first(archive, key)
            first_ng = _first(nogood_head, key)
            if (head >= 0 and _kept_dominates(
                head, archive_next, lab_L, lab_k, lab_mass, lab_arc, lab_vmin, lab_hmin,
                lab_ss, lab_sn, sv, sh, sm,
                nL, k + 1, new_mass, arc_in, nv, nh, new_v, new_h, new_m, 0, count,
                has_pairs, node_of_arc, pair_ptr, pair_length,
            )) or (first_ng >= 0 and _kept_dominates(
                first_ng, nogoods.next, nogoods.L, nogoods.k, nogoods.mass, nogoods.arc,
                nogoods.vmin, nogoods.hmin, nogoods.ss, nogoods.sn, nogoods.sv, nogoods.sh,
                nogoods.sm, nL, k + 1, new_mass, arc_in, nv, nh, new_v, new_h, new_m, 0, count,
                has_pairs, node_of_arc, pair_ptr, pair_length,
            )):  # fmt: skip
                continue
            # A new label: kept in the archive and queued.
            child = len(lab_L)
            (sv, sh, sm), used = _keep(
                store, (sv, sh, sm), used, new_v, new_h, new_m, count, nL, k + 1, j, arc_in,
                lab, mask | (np.int64(1) << bit) if bit >= 0 else mask, new_mass, nv, nh, g,
                head,
            )  # fmt: skip
            lab_kmask.append(mask)
            archive[key] = child
            heapq.heappush(heap, (nL + g[len(g) - 1], np.int64(counter), np.int64(child)))
            counter += 1
        if escape >= 0:
            break
    if escape >= 0:
        points = [escape_to]
        e = escape
        while e > 0:
            points.append(lab_node[e])
            e = lab_parent[e]
        path = np.empty(len(points), np.int64)
        for i in range(len(points)):
            path[i] = points[len(points) - 1 - i]
        return (False, labels, path, *nothing)
    if not exhausted:
        return (False, labels, empty_i, *nothing)
    # Covered: every partial route expanded is covered too (a nogood from now on).
    ne = len(expanded)
    e_node = np.empty(ne, np.int64)
    e_mask = np.empty(ne, np.int64)
    e_L = np.empty(ne)
    e_k = np.empty(ne, np.int64)
    e_mass = np.empty(ne)
    e_arc = np.empty(ne, np.int64)
    e_vmin = np.empty(ne)
    e_hmin = np.empty(ne)
    e_ss = np.empty(ne, np.int64)
    e_sn = np.empty(ne, np.int64)
    total = 0
    for x in range(ne):
        total += lab_sn[expanded[x]]
    e_sv = np.empty(total)
    e_sh = np.empty(total)
    e_sm = np.empty(total)
    at = 0
    for x in range(ne):
        lab = expanded[x]
        e_node[x] = lab_node[lab]
        e_mask[x] = lab_kmask[lab]
        e_L[x] = lab_L[lab]
        e_k[x] = lab_k[lab]
        e_mass[x] = lab_mass[lab]
        e_arc[x] = lab_arc[lab]
        e_vmin[x] = lab_vmin[lab]
        e_hmin[x] = lab_hmin[lab]
        e_ss[x] = at
        e_sn[x] = lab_sn[lab]
        for c in range(lab_sn[lab]):
            e_sv[at] = sv[lab_ss[lab] + c]
            e_sh[at] = sh[lab_ss[lab] + c]
            e_sm[at] = sm[lab_ss[lab] + c]
            at += 1
    added = (e_node, e_mask, e_L, e_k, e_mass, e_arc, e_vmin, e_hmin, e_ss, e_sn, e_sv, e_sh, e_sm)
    return (True, labels, empty_i, *added)


@njit(cache=True)
def link(head: Dict, nxt: np.ndarray, node: np.ndarray, mask: np.ndarray, base: int) -> None:
    """Link entries base .. base + len(node) - 1 of the nogood store into ``head``."""
    for x in range(len(node)):
        key = (node[x], mask[x])
        nxt[base + x] = head.get(key, -1)
        head[key] = base + x


class CompiledProbes:
    """The Python side of ``probe``: the arrays of one prober's relaxation (``bnb._Prober``),
    made once, the found routes' arrays, made again when they change, and the nogood store.

    ``ctx`` is the prober's context (``bnb._Context`` of the relaxation it probes in),
    ``critical`` its critical points (at most 62: a bit each)."""

    def __init__(self, ctx, critical: frozenset[int]) -> None:  # noqa: ANN001 (bnb._Context)
        graph = ctx.graph
        scenario = ctx.scenario
        self.ctx = ctx
        self.crit_bit = np.full(scenario.n, -1, np.int64)
        for b, point in enumerate(sorted(critical)):
            self.crit_bit[point] = b
        pairs = ctx.pair_floor
        self.graph = graph.record(
            scenario, ctx.unreliable, ctx.params.p_success, ctx.params.residual_m, ctx.kmax,
            self.crit_bit,
        )  # fmt: skip
        self.to_go = ctx.G.record()
        self.pairs = NO_PAIRS if pairs is None else pairs.record()
        self._failures: Failures = NO_FAILURES
        self._bounds: object = None  # the FailureBounds they were made of (None: none yet)
        self._found: object = None
        self._incumbents: Incumbents | None = None
        # The nogood store: (point, mask) -> last entry, entries linked back.
        self.head = new_key_dict()
        self.entries = 0
        self.states = 0
        self.store = empty_nogoods(256, 1024)

    def _failure_bounds(self) -> Failures:
        """The failure bounds' record, asked again until the bounds are made (``bnb._Context
        .failures``: once the probes have spent enough labels)."""
        fb = self.ctx.failures(0)  # (the prober's: it counts the probes' labels itself)
        if fb is not self._bounds:
            self._bounds = fb
            self._failures = NO_FAILURES if fb is None else fb.record()
        return self._failures

    def _incumbent_record(self, inc) -> Incumbents:  # noqa: ANN001 (bnb._Incumbents)
        """The found routes' arrays and the ceiling per level, made again when they change
        (``_Incumbents.add`` makes a new list)."""
        if inc.found is not self._found:
            self._found = inc.found
            length = np.array([f.length for f in inc.found], float)
            k = np.array([f.corrections for f in inc.found], np.int64)
            p = np.array([f.probability for f in inc.found], float)
            levels = np.array(inc.levels(), float)
            ceiling = self.ctx.ceiling
            if ceiling is None:
                ceil_rows = np.empty((0, self.ctx.kmax + 1))
            else:
                ceil_rows = np.vstack(
                    [ceiling.least_above(float(lo)) for lo in levels]
                    + [ceiling.least_above(-np.inf)]
                )
            self._incumbents = Incumbents(
                ceiling is not None, ceil_rows, length, k, p, np.sort(p),
                np.argsort(p, kind="stable").astype(np.int64), levels,
            )  # fmt: skip
        return self._incumbents

    def __call__(
        self,
        inc,  # noqa: ANN001 (bnb._Incumbents)
        L: float,
        node: int,
        k: int,
        states: dict,
        arc: int,
        path: tuple[int, ...],
        to_go: np.ndarray,
        max_labels: int,
    ) -> tuple[bool, int, tuple[int, ...]]:
        """(covered, labels, the escaping completion's points after ``path``, empty if none)."""
        bits = self.crit_bit
        before = 0
        for point in path[:-1]:
            if bits[point] >= 0:
                before |= 1 << int(bits[point])
        mask = before | (1 << int(bits[node]) if bits[node] >= 0 else 0)
        sv = np.array([s[0] for s in states], float)
        sh = np.array([s[1] for s in states], float)
        sm = np.array(list(states.values()), float)
        route = Partial(
            float(L), int(node), int(k), sv, sh, sm, int(arc), before, mask,
            np.asarray(to_go, float),
        )  # fmt: skip
        out = probe(
            self.graph, self.to_go, self.pairs, self._failure_bounds(),
            self._incumbent_record(inc), route, self.head, self.store, int(max_labels),
        )  # fmt: skip
        covered, labels, escape = bool(out[0]), int(out[1]), out[2]
        if covered and labels:
            self._add(*out[3:])
        return covered, labels, tuple(int(p) for p in escape)

    def _add(self, node, mask, L, k, mass, arc, vmin, hmin, ss, sn, sv, sh, sm) -> None:  # noqa: ANN001
        """Join the expanded partial routes of a covered probe to the nogoods."""
        n, s = len(node), len(sv)
        cap_e, cap_s = len(self.store.L), len(self.store.sv)
        if self.entries + n > cap_e or self.states + s > cap_s:
            grown = empty_nogoods(max(2 * cap_e, self.entries + n), max(2 * cap_s, self.states + s))
            for old, new in zip(self.store, grown):
                new[: len(old)] = old
            self.store = grown
        nxt, sL, sk, smass, sarc, svmin, shmin, sss, ssn, ssv, ssh, ssm = self.store
        e0, e1, s0, s1 = self.entries, self.entries + n, self.states, self.states + s
        sL[e0:e1], sk[e0:e1], smass[e0:e1], sarc[e0:e1] = L, k, mass, arc
        svmin[e0:e1], shmin[e0:e1], sss[e0:e1], ssn[e0:e1] = vmin, hmin, ss + s0, sn
        ssv[s0:s1], ssh[s0:s1], ssm[s0:s1] = sv, sh, sm
        link(self.head, nxt, node, mask, e0)
        self.entries, self.states = e1, s1

