"""How far a method's front is from the exact one."""

from __future__ import annotations

import math
from dataclasses import dataclass

Front = list[tuple[float, int, tuple[int, ...]]]

# Lengths equal to this many metres are the same front point (the MILP is optimal to 1e-6 m).
SAME_M = 1e-6


@dataclass(frozen=True)
class Comparison:
    """Per exact front point (L*, k): the method's shortest route with at most k corrections.

    ``found``: exact points the method matches; ``missed``: exact points for which the method
    has no route with at most k corrections; gaps are (L − L*) / L* in % over the points not
    missed (NaN when all are missed); ``equal``: the fronts are the same; ``beats_exact``: the
    method reports a route shorter than the exact front allows (a bug somewhere).
    """

    exact_points: int
    found: int
    missed: int
    gap_max_pct: float
    gap_mean_pct: float
    equal: bool
    beats_exact: bool


def shortest_within(front: Front, k: int) -> float:
    return min((length for length, c, _ in front if c <= k), default=math.inf)


def compare(front: Front, exact: Front) -> Comparison:
    gaps, found, missed, beats = [], 0, 0, False
    for length, k, _ in exact:
        mine = shortest_within(front, k)
        if math.isinf(mine):
            missed += 1
            continue
        if mine < length - SAME_M:
            beats = True
        if abs(mine - length) <= SAME_M:
            found += 1
        gaps.append(max(0.0, (mine - length) / length * 100.0))
    equal = [k for _, k, _ in front] == [k for _, k, _ in exact] and all(
        abs(a[0] - b[0]) <= SAME_M for a, b in zip(front, exact)
    )
    return Comparison(
        len(exact),
        found,
        missed,
        max(gaps) if gaps else math.nan,
        sum(gaps) / len(gaps) if gaps else math.nan,
        equal,
        beats,
    )
