"""What a branch and bound stopped by its budget has still proven, route by route.

A front route with a gap of 0 is the shortest route with at most its corrections and at least
its probability — but the front around it may still miss routes: best-first search finds the
short routes with many corrections first, and a budget can stop it before the longer routes
with fewer corrections (or more likely to arrive) are found. Calling such a route "optimal"
would be a claim about one point while the user reads it as a claim about the front. So a
route is *settled* only when no open partial route can still lead to a front route with no more
corrections than it, nor (with the probability objective) one at least as likely to arrive.

An open partial route (L so far, k corrections, bound G(m) per number m of further corrections,
its surviving mass) can still lead to a front route with k + m corrections exactly when
L + G(m) is below the best found length with <= k + m corrections and at least that mass — the
test ``_Incumbents.covers`` makes for every m at once.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from gcs_planner.core.probability import PROB_EPS


def _padded(live: Sequence[tuple[float, int, np.ndarray, float]]) -> np.ndarray:
    """The open partial routes' bounds per m as one matrix, each row carried on with its last
    entry (which holds for every larger m)."""
    width = max(len(t) for _, _, t, _ in live)
    rows = np.empty((len(live), width))
    for i, (_, _, t, _) in enumerate(live):
        rows[i, : len(t)] = t
        rows[i, len(t) :] = t[-1]
    return rows


def lower_bounds(
    front: Sequence, live: Sequence[tuple[float, int, np.ndarray, float]]
) -> list[float]:
    """Per front route g: the least length an open partial route can still reach with <= g's
    corrections and at least g's probability (g's own length when none can): the proven lower
    bound of g's point of the front. The bounds per m never grow with m (more corrections
    allowed), so "at most c - k more" reads the entry at c - k."""
    if not live:
        return [g.length for g in front]
    rows = _padded(live)
    L = np.array([x[0] for x in live])
    k = np.array([x[1] for x in live])
    mass = np.array([x[3] for x in live])
    at = np.arange(len(live))
    out = []
    for g in front:
        more = g.corrections - k
        usable = (more >= 0) & (mass >= g.probability - PROB_EPS)
        reach = L + rows[at, np.clip(more, 0, rows.shape[1] - 1)]
        out.append(min(g.length, float(reach[usable].min())) if usable.any() else g.length)
    return out


def fewest_open_corrections(
    L: float, k: int, to_go: np.ndarray, mass: float, best: Callable[[float], np.ndarray], kmax: int
) -> float:
    """The fewest corrections of a route an open partial route can still add to the front
    (inf when it can add none)."""
    m = min(len(to_go), kmax - k + 1)
    if m <= 0:
        return math.inf
    open_m = np.flatnonzero(L + to_go[:m] < best(mass)[k : k + m])
    return float(k + open_m[0]) if len(open_m) else math.inf


def settled(
    front: Sequence,
    live: Sequence[tuple[float, int, np.ndarray, float]],
    best: Callable[[float], np.ndarray],
    kmax: int,
    probability: bool,
) -> list[bool]:
    """Per front route (``corrections``, ``probability`` attributes): whether it is settled.

    ``live``: the open partial routes as (L, k, G per m, mass); ``best(mass)[c]``: the least
    found length with <= c corrections and probability >= mass."""
    if not front:  # nothing to settle (a search stopped before any route: 250,000 open)
        return []
    fewest = math.inf
    likeliest = -math.inf
    for L, k, to_go, mass in live:
        c = fewest_open_corrections(L, k, to_go, mass, best, kmax)
        if c < math.inf:
            fewest = min(fewest, c)
            likeliest = max(likeliest, mass)
    return [
        g.corrections < fewest and (not probability or likeliest < g.probability - PROB_EPS)
        for g in front
    ]
