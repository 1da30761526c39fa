"""Dominance between partial routes, compiled (numba): ``bnb._dominated_by`` of a new partial
route by those kept at its key (a search's archive, or the probes' nogoods), with the pair
relaxation's margin between arcs and Hall's condition between error-state distributions
(``bnb._stochastically_dominates``). Shared by the compiled probes and searches.
"""

from __future__ import annotations

import numpy as np

from gcs_planner.core.kernel_records import Pairs
from gcs_planner.core.probability import PROB_EPS
from gcs_planner.runtime.jit import inner

MAX_UNIONS = 256  # as bnb.MAX_UNIONS


@inner
def margin(pairs: Pairs, kept: int, new: int) -> float:
    """PairBounds.margin (0 without pairs or for the same arc)."""
    if not pairs.present or kept == new:
        return 0.0
    node_of_arc, pair_ptr, pair_length = pairs.node_of_arc, pairs.pair_ptr, pairs.length
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


@inner
def stochastically_dominates(
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


@inner
def kept_dominates(
    kept,  # noqa: ANN001 (a Nogoods record, or a search's Labels: the fields read are the same)
    kept_v: np.ndarray,
    kept_h: np.ndarray,
    kept_m: np.ndarray,
    first: int,
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
    pairs: Pairs,
) -> bool:
    """Whether one of the partial routes ``kept`` linked back from entry ``first`` (their
    states in kept_v/kept_h/kept_m) dominates the new one (``bnb._dominated_by``): L, k, mass,
    the arc flown last, its least v and h, its states sv/sh/sm[s:s + n]."""
    # (The fields read once: a field read in the loop costs reference counts there.)
    kL, kk, kmass, karc, kvmin, khmin = kept.L, kept.k, kept.mass, kept.arc, kept.vmin, kept.hmin
    kss, ksn, nxt = kept.ss, kept.sn, kept.next
    e = first
    while e >= 0:
        # The scalars first: most kept routes fail them, and the states are compared only
        # where they pass.
        if (
            kL[e] <= L and kk[e] <= k and kmass[e] >= mass - PROB_EPS and kvmin[e] <= v
            and khmin[e] <= h
        ):  # fmt: skip
            shift = margin(pairs, karc[e], arc)
            if (
                kL[e] + shift <= L
                and kvmin[e] + shift <= v
                and khmin[e] + shift <= h
                and stochastically_dominates(
                    kept_v, kept_h, kept_m, kss[e], ksn[e], shift, sv, sh, sm, s, n
                )
            ):
                return True
        e = nxt[e]
    return False
