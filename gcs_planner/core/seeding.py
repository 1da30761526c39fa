"""The two-objective straight-leg front as a start and a floor for the harder searches.

Every route flown with turns, or with unreliable correction points, is still a route of the
two-objective straight-leg model, and no shorter there: its straight legs are no longer than its
flown ones, and the branch in which every correction succeeds carries the least error of all
(a failed correction leaves min(e, r) >= 0), so a route with any chance to arrive is feasible
when corrections are certain. Hence:

* the least straight-leg length with <= c corrections bounds from below every route with <= c
  corrections, whatever the legs and the probability (``floor``);
* that front's routes, flown under the harder model, are routes of it: they start the branch
  and bound as incumbents (``seeds``) — in particular the fewest-corrections end of the front,
  which a best-first search by length reaches last.

The layered search proves that front quickly (seconds at 20,000 points), so it costs little
beside the branch and bound it strengthens.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gcs_planner.core.search import straight_front
from gcs_planner.scenario.model import Scenario


@dataclass(frozen=True)
class CertainFront:
    seeds: tuple[tuple[int, ...], ...]
    # least[c]: the least straight-leg length with <= c corrections (inf where none).
    least: np.ndarray

    def floor(self, corrections: int) -> float:
        """A lower bound on the length of any route with <= ``corrections`` corrections."""
        if corrections < 0:
            return float("inf")
        return float(self.least[min(corrections, len(self.least) - 1)])


def certain_front(scenario: Scenario, max_corrections: int | None = None) -> CertainFront:
    """The exact (length, corrections) front with straight legs and certain corrections."""
    straight = scenario.with_params(turn_radius=0.0)
    res = straight_front(straight, max_corrections=max_corrections)
    kmax = max((fp.corrections for fp in res.front), default=0)
    least = np.full(kmax + 1, np.inf)
    for fp in res.front:
        least[fp.corrections] = min(least[fp.corrections], fp.length)
    np.minimum.accumulate(least, out=least)
    return CertainFront(tuple(fp.points for fp in res.front), least)
