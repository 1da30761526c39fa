"""Confidence intervals for success rates of seeded replays (the planner's Monte Carlo and the
mock vehicle's), in one place so both report the same interval for the same counts."""

from __future__ import annotations

import math
from statistics import NormalDist


def wilson_interval(successes: int, runs: int, confidence: float) -> tuple[float, float]:
    """Wilson score interval of a binomial rate: unlike the normal approximation it stays in
    [0, 1] and is sound for rates near 0 or 1, where replays of planned routes mostly lie."""
    z = NormalDist().inv_cdf(0.5 + confidence / 2.0)
    rate = successes / runs
    z2n = z * z / runs
    centre = (rate + z2n / 2.0) / (1.0 + z2n)
    half = z / (1.0 + z2n) * math.sqrt(rate * (1.0 - rate) / runs + z2n / (4.0 * runs))
    # At 0 or all successes the interval ends exactly at 0 or 1; rounding must not move it.
    low = 0.0 if successes == 0 else max(0.0, centre - half)
    high = 1.0 if successes == runs else min(1.0, centre + half)
    return low, high
