"""The routes a search has found and what they say of the partial routes still open: whether
every completion of one is already matched (``_Incumbents``), and what a relaxation's proven
front says of every route (``Ceiling``)."""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from gcs_planner.core.proof import PROB_EPS


@dataclass(frozen=True)
class Found:
    length: float
    corrections: int
    probability: float
    points: tuple[int, ...]


@dataclass
class BnbResult:
    front: list[Found]
    lower_bounds: list[float]
    optimal: bool
    labels: int
    seconds: float
    exhausted: bool
    # Over the open labels no front point dominates: how many, and the least length they can
    # still reach (inf when there are none: the front is then complete).
    open_labels: int = 0
    open_bound: float = math.inf
    # Straight legs: rounds of decremental state-space relaxation and the critical points.
    rounds: int = 1
    critical: tuple[int, ...] = ()
    # Per front point: whether it is proven to belong to the front *and* no open partial route
    # can still lead to a front route with no more corrections (or, with the probability
    # objective, at least its probability). See ``settled``.
    proven: list[bool] | None = None
    # Labels the probes of this search expanded (``_Prober``).
    probe_labels: int = 0
    # What the time limit cut short or skipped before the search (in words; empty: nothing).
    # Every bound stays admissible without it: only the proof gets harder.
    cut: tuple[str, ...] = ()


def _least_length(front: Sequence[Found], corrections: int, probability: float) -> float:
    """The least length on ``front`` with at most ``corrections`` and at least ``probability``."""
    return min(
        (
            f.length
            for f in front
            if f.corrections <= corrections and f.probability >= probability - PROB_EPS
        ),
        default=math.inf,
    )


def _dominated(found: Sequence[Found], length: float, k: int, prob: float) -> bool:
    """Whether a found route is at least as good as (length, k, prob) on every objective."""
    return _least_length(found, k, prob) <= length


class _Incumbents:
    """The routes found so far, asked one question many times: is every route a partial route
    can still become — (at least L + G_j(e, m) metres, k + m corrections, at most its mass) for
    each m — already matched by a found route?"""

    def __init__(self, kmax: int) -> None:
        self.kmax = kmax
        self.found: list[Found] = []
        # best() per number of found routes at least so likely (which ones: the likeliest).
        self._best: dict[int, np.ndarray] = {}
        self._probabilities: list[float] = []  # the found routes', ascending
        self._levels: list[float] | None = None

    def add(self, new: Found) -> None:
        self.found = [
            g for g in self.found if not _dominated([new], g.length, g.corrections, g.probability)
        ]
        self.found.append(new)
        self._best.clear()
        self._probabilities = sorted(f.probability for f in self.found)
        self._levels = None

    def offer(self, route: Found | None) -> None:
        """Add ``route`` (a seed; None: none) unless a found route is at least as good."""
        if route is not None and not _dominated(
            self.found, route.length, route.corrections, route.probability
        ):
            self.add(route)

    def levels(self) -> list[float]:
        """The found routes' probabilities, largest first, equal ones (within PROB_EPS) once."""
        if self._levels is None:
            levels: list[float] = []
            for p in sorted((f.probability for f in self.found), reverse=True):
                if not levels or p < levels[-1] - PROB_EPS:
                    levels.append(p)
            self._levels = levels
        return self._levels

    def best(self, mass: float) -> np.ndarray:
        """best[c] = the least length of a found route with <= c corrections and a probability
        of at least ``mass`` (inf if none)."""
        likely = len(self.found) - bisect.bisect_left(self._probabilities, mass - PROB_EPS)
        b = self._best.get(likely)
        if b is None:
            b = np.full(self.kmax + 1, np.inf)
            for f in self.found:
                if f.probability >= mass - PROB_EPS and f.corrections <= self.kmax:
                    b[f.corrections] = min(b[f.corrections], f.length)
            np.minimum.accumulate(b, out=b)
            self._best[likely] = b
        return b

    def covers(self, length: float, k: int, to_go: np.ndarray | None, mass: float) -> bool:
        """Whether every completion of a partial route (length L so far, k corrections, the
        bound ``to_go`` = G_j(e, m) per m) is dominated by a found route, or none exists."""
        if to_go is None:
            return True
        m = min(len(to_go), self.kmax - k + 1)
        if m <= 0:
            return True
        return bool((length + to_go[:m] >= self.best(mass)[k : k + m]).all())

    def least_open(self, length: float, k: int, to_go: np.ndarray | None, mass: float) -> float:
        """The least length L + G_j(e, m) over the numbers m of further corrections for which
        ``covers`` fails (inf when it holds): no route this partial route still leads to and
        that no found route dominates is shorter. Found routes only accrue, so the value only
        grows while the partial route waits in the queue."""
        if to_go is None:
            return math.inf
        m = min(len(to_go), self.kmax - k + 1)
        if m <= 0:
            return math.inf
        reach = length + to_go[:m]
        reach = reach[reach < self.best(mass)[k : k + m]]
        return float(reach.min()) if len(reach) else math.inf

    def covers_by_level(
        self,
        length: float,
        k: int,
        mass: float,
        bound: Callable[[float], np.ndarray | None],
        ceiling: Ceiling | None = None,
    ) -> bool:
        """``covers`` with a bound per probability level: ``bound(gap)`` bounds per m the
        continuations that lose less than ``gap`` of the mass (None: there are none), and
        ``ceiling`` bounds the whole length of a route by its corrections and probability.

        A continuation ending with probability pi in (lo, hi] (lo, hi consecutive found
        levels, pi measured with PROB_EPS) is matched only by found routes at least hi likely,
        and it loses less than mass - lo: so each interval is tested with its own bound and its
        own found routes. Above the likeliest found route nothing matches, so a partial route
        that may still end there stays open unless the ceiling rules such routes out."""
        levels = self.levels()
        width = self.kmax - k + 1
        if width <= 0:
            return True
        for hi, lo in zip([None, *levels], [*levels, None]):
            floor = 0.0 if lo is None else lo + PROB_EPS
            if floor >= mass:
                continue  # every continuation ends at most lo + PROB_EPS likely: lower intervals
            to_go = bound(mass - floor)
            if to_go is None:
                continue
            reach = np.empty(width)
            m = min(len(to_go), width)
            reach[:m] = length + to_go[:m]
            reach[m:] = length + to_go[-1]
            if ceiling is not None:
                above = -math.inf if lo is None else lo  # the last interval: every route
                np.maximum(reach, ceiling.least_above(above)[k:], out=reach)
            best = np.full(width, np.inf) if hi is None else self.best(hi)[k:]
            if not (reach >= best).all():
                return False
        return True


class Ceiling:
    """What the exact front of a relaxation says of every route: each route of the model is,
    relaxed, weakly dominated by a point of that front, and relaxing a route shortens it and
    raises its probability. So a route with c corrections and a probability above ``lo`` is at
    least as long as the shortest front point of the relaxation with <= c corrections and a
    probability of at least ``lo`` (inf: no such route)."""

    def __init__(self, front: Sequence[Found], kmax: int) -> None:
        self.front = list(front)
        self.kmax = kmax
        self._least: dict[float, np.ndarray] = {}

    def least_above(self, lo: float) -> np.ndarray:
        """Per number of corrections c = 0..kmax: the least length of a route with c
        corrections whose probability exceeds ``lo`` + PROB_EPS. Probabilities reached in
        different orders differ by far less than PROB_EPS / 2, so a relaxed front point counts
        when it exceeds ``lo`` + PROB_EPS / 2: rounding can only weaken the bound."""
        least = self._least.get(lo)
        if least is None:
            least = np.full(self.kmax + 1, np.inf)
            for f in self.front:
                if f.probability > lo + PROB_EPS / 2 and f.corrections <= self.kmax:
                    least[f.corrections] = min(least[f.corrections], f.length)
            np.minimum.accumulate(least, out=least)
            self._least[lo] = least
        return least
