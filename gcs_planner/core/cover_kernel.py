"""Whether the found routes cover a partial route, compiled (numba): the found routes' best
length per number of corrections and probability (``bnb._Incumbents``), the test of a bound to
go against them, and the probes' test per probability level with the failure bounds
(``FailureBounds.bound``) and the relaxation's ceiling (``_Incumbents.covers_by_level``).
Shared by the compiled probes (``probe_kernel``) and searches (``search_kernel``).
"""

from __future__ import annotations

import numpy as np

from gcs_planner.core.kernel_records import Failures
from gcs_planner.core.probability import PROB_EPS
from gcs_planner.runtime.jit import inner

MASS_SLACK = 1e-13  # as failure_bounds._MASS_SLACK


@inner
def row(indptr: np.ndarray, e_max: np.ndarray, j: int, e: float) -> int:
    """CostToGo._row: the first row of node j whose E is >= e, -1 when none."""
    lo = indptr[j]
    hi = indptr[j + 1]
    i = lo + np.searchsorted(e_max[lo:hi], e)
    return i if i < hi else -1


@inner
def larger(a: np.ndarray, b: np.ndarray) -> np.ndarray:
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


@inner
def best_rows(inc_len: np.ndarray, inc_k: np.ndarray, order: np.ndarray, kmax: int) -> np.ndarray:
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


@inner
def likely(probs_sorted: np.ndarray, mass: float) -> int:
    """How many found routes are at least ``mass`` likely (within PROB_EPS)."""
    return len(probs_sorted) - np.searchsorted(probs_sorted, mass - PROB_EPS)


@inner
def covers(length: float, k: int, to_go: np.ndarray, best: np.ndarray, kmax: int) -> bool:
    """_Incumbents.covers with ``best`` the row for the partial route's mass."""
    m = min(len(to_go), kmax - k + 1)
    if m <= 0:
        return True
    for i in range(m):
        if not (length + to_go[i] >= best[k + i]):
            return False
    return True


@inner
def dominated_end(
    inc_len: np.ndarray, inc_k: np.ndarray, inc_p: np.ndarray, length: float, k: int, p: float
) -> bool:
    """bnb._dominated: a found route with <= k corrections, at least p likely, no longer."""
    least = np.inf
    for f in range(len(inc_len)):
        if inc_k[f] <= k and inc_p[f] >= p - PROB_EPS and inc_len[f] < least:
            least = inc_len[f]
    return least <= length


@inner
def forced(weight: float, gap: float, failures: int, q_fail: float) -> int:
    """FailureBounds.forced: the first failures a state of mass ``weight`` must survive in a
    continuation that loses less than ``gap`` (-1: none, the state may die whole)."""
    if weight < gap + MASS_SLACK:
        return -1
    q = 0
    while q < failures and weight * q_fail ** float(q + 1) >= gap + MASS_SLACK:
        q += 1
    return q


@inner
def failure_rows(
    failures: Failures,
    at: int,
    sv: np.ndarray,
    sh: np.ndarray,
    sm: np.ndarray,
    s: int,
    n: int,
    gap: float,
) -> np.ndarray:
    """FailureBounds.bound (an empty array for None) of the states sv/sh/sm[s:s + n] at ``at``
    for a continuation that loses less than ``gap``."""
    f_ptr, f_emax, f_table = failures.to_go
    f_n, f_failures, f_qfail = failures.n, failures.failures, failures.q_fail
    carried_h = failures.is_v[at]  # a V point resets v: h is carried, and vice versa
    e_min = np.inf
    for i in range(n):
        e = sh[s + i] if carried_h else sv[s + i]
        if e < e_min:
            e_min = e
    r = row(f_ptr, f_emax, at, e_min)
    if r < 0:
        return np.empty(0)
    out = f_table[r].copy()
    for i in range(n):
        q = forced(sm[s + i], gap, f_failures, f_qfail)
        if q < 0:
            continue
        e = sh[s + i] if carried_h else sv[s + i]
        r = row(f_ptr, f_emax, q * f_n + at, e)
        if r < 0:
            return np.empty(0)
        survived = f_table[r]  # the bound when its first q failures are survived
        for m in range(len(out)):
            if survived[m] > out[m] or survived[m] != survived[m]:
                out[m] = survived[m]
    return out


@inner
def level_tables(
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
    past the end of a bound (constant from there) ``covers_by_level`` needs only these."""
    nlev = len(levels)
    level_best = np.full((nlev + 1, kmax + 1), np.inf)
    next_bad = np.empty((nlev + 1, kmax + 2), np.int64)
    for i in range(nlev + 1):
        if i > 0:
            best = best_rows[likely(probs_sorted, levels[i - 1])]
            for c in range(kmax + 1):  # (not a row assignment: see expand_kernel.new_labels)
                level_best[i, c] = best[c]
        next_bad[i, kmax + 1] = kmax + 1
        for c in range(kmax, -1, -1):
            bad = not has_ceil or ceil_rows[i, c] < level_best[i, c]
            next_bad[i, c] = c if bad else next_bad[i, c + 1]
    return level_best, next_bad


@inner
def covers_by_level(
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
    failures: Failures,
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
    ceiling below best[c] (``level_tables``)."""
    width = kmax - k + 1
    if width <= 0:
        return True
    nlev = len(levels)
    # The bound depends on the gap only through the failures each state must survive: levels
    # that force the same ones share it (as bnb's memo per forced tuple).
    survive = np.full(n, -2, np.int64)
    bound = to_go
    for i in range(nlev + 1):
        floor = levels[i] + PROB_EPS if i < nlev else 0.0
        if floor >= mass:
            continue
        if failures.present:
            same = survive[0] != -2
            for x in range(n):
                q = forced(sm[s + x], mass - floor, failures.failures, failures.q_fail)
                if q != survive[x]:
                    same = False
                    survive[x] = q
            if not same:
                rows = failure_rows(failures, at, sv, sh, sm, s, n, mass - floor)
                bound = rows if len(rows) == 0 else larger(rows, to_go)
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
