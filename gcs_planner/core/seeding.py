"""The two-objective heading-free front as a start and a floor for the harder searches.

Every route flown with turns, or with unreliable correction points, is still a route of the
two-objective model whose legs are the leg model's heading-free lower bounds, and no shorter
there: those legs are no longer than its flown ones, and the branch in which every correction
succeeds carries the least error of all (a failed correction leaves min(e, r) >= 0), so a route
with any chance to arrive is feasible when corrections are certain. Hence:

* the least straight-leg length with <= c corrections bounds from below every route with <= c
  corrections, whatever the legs and the probability (``floor``);
* that front's routes, flown under the harder model, are routes of it: they start the branch
  and bound as incumbents (``seeds``) — in particular the fewest-corrections end of the front,
  which a best-first search by length reaches last.

The other end of the probability axis: routes that use no unreliable point arrive with
probability 1, and the two-objective front of the scenario without its unreliable points is
made of such routes (``reliable_seeds``). Without them the search knows no certain route with
few corrections until it stumbles on one, and until then every partial route that has kept all
its mass and can still end with few corrections stays open, however long (a 300 km corridor of
3,000 points: 49,000 partial routes open after 5,000 labels; with them it is proven in some
7,000 labels). Seeds only add incumbents, each evaluated exactly: they never change the front.

Only the layered search's first round runs (the compiled kernel on large maps): a front over
walks, which may revisit points. Its lengths still bound simple routes from below (every route
is a walk), and its simple routes are routes; the later rounds that make it exact cost more on
long sparse corridors than the seeds are worth.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gcs_planner.core.reach import ReachGraph, use_compiled
from gcs_planner.core.search import straight_front
from gcs_planner.scenario.model import Scenario


@dataclass(frozen=True)
class CertainFront:
    seeds: tuple[tuple[int, ...], ...]
    # least[c]: the least straight-leg length with <= c corrections (inf where none).
    least: np.ndarray
    # The scenario's reach graph, when the search made it (or was given it); None when it
    # searched only the points near the straight line from A to B (large maps).
    graph: ReachGraph | None = field(default=None, repr=False, compare=False)

    def floor(self, corrections: int) -> float:
        """A lower bound on the length of any route with <= ``corrections`` corrections."""
        if corrections < 0:
            return float("inf")
        return float(self.least[min(corrections, len(self.least) - 1)])


def certain_front(
    scenario: Scenario, max_corrections: int | None = None, graph: ReachGraph | None = None
) -> CertainFront:
    """The (length, corrections) front over walks with certain corrections and heading-free
    legs, each as long as the leg model's lower bound (the chord for straight and cs3d legs; for
    airplane legs the chord or the climb at the limit angle, whichever is longer): its simple
    routes, and per number of corrections a lower bound on every route. The reach graph is made
    of those bounds, so the layered search over it is that front.

    Not the straight-leg front of a copy with R = 0: airplane legs with R = 0 cannot fly a leg
    too steep for its length, which a helix flies with R > 0, so that front is no floor.
    ``graph``: the scenario's reach graph, when the caller has it already; without one, large
    maps search only the points that can lie on a front route (``straight_search._focused``)
    and the graph over every point is made only where that cannot be proven (then returned)."""
    res = straight_front(
        scenario,
        graph,
        max_corrections=max_corrections,
        max_rounds=1,
        focus=use_compiled(scenario.n, None),
    )
    kmax = max((fp.corrections for fp in res.front), default=0)
    least = np.full(kmax + 1, np.inf)
    for fp in res.front:
        least[fp.corrections] = min(least[fp.corrections], fp.length)
    np.minimum.accumulate(least, out=least)
    simple = tuple(fp.points for fp in res.front if len(set(fp.points)) == len(fp.points))
    return CertainFront(simple, least, res.graph)


def reliable_seeds(
    scenario: Scenario, max_corrections: int | None = None
) -> tuple[tuple[int, ...], ...]:
    """The simple routes of the (length, corrections) front over walks of the scenario without
    its unreliable points (indices of ``scenario``): routes certain to arrive when their legs are
    flown as bounded, one per number of corrections. Empty when every point is reliable (the
    certain front is that front already)."""
    keep = np.flatnonzero(~np.asarray(scenario.unreliable, dtype=bool))
    if len(keep) == scenario.n:
        return ()
    res = straight_front(scenario.subset(keep), max_corrections=max_corrections, max_rounds=1)
    return tuple(
        tuple(int(keep[i]) for i in fp.points)
        for fp in res.front
        if len(set(fp.points)) == len(fp.points)
    )
