"""The points a front route can pass, for the branch and bound on large maps.

The straight search focuses on the ellipsoid with foci A and B that its own bound allows
(``straight_search._focused``). The branch and bound (turns, the probability objective) can do
the same once it knows a route s that no front route is longer than:

* s has the fewest corrections any route can have, k: the two-objective front over walks with
  the heading-free lower bounds of the legs (``seeding.certain_front``) has no point with fewer,
  and every route flown with turns, and every route with any chance to arrive, is one of its
  walks. So every route has at least k corrections.
* s is feasible as flown, and, with the probability objective, certain to arrive (it passes no
  unreliable point).

Then a route longer than s has at least as many corrections, is longer and is no likelier: s
dominates it. So no front route is longer than s, and every point p of a front route has
|AP| + |PB| <= length(s) (legs are never shorter than their chords). The front searched over
those points (and A and B) is the whole front: its routes are routes, s is among them, and a
route that dominates one of them is no longer than s, so it is among them too.

On dense maps that ellipsoid holds a few per cent of the points (random 20,000 points, two
objectives with turns: about 300), and the bounds the branch and bound builds first (the
cost-to-go over every point, seconds a layer) shrink with it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from gcs_planner.core.bnb import flown_route
from gcs_planner.core.reach import COMPILED_FROM_POINTS
from gcs_planner.core.seeding import CertainFront
from gcs_planner.scenario.model import Scenario

# Maps this large are focused, as the straight search's (from where its kernels run): on smaller
# ones the branch and bound's set-up takes a fraction of a second over every point.
FOCUS_FROM = COMPILED_FROM_POINTS
# Relative rounding slack that keeps a point on the ellipsoid's surface inside.
_ROUNDING = 1e-9


def front_bound(
    scenario: Scenario,
    certain: CertainFront,
    routes: Sequence[Sequence[int]],
    probability: bool,
) -> float | None:
    """The least flown length of those of ``routes`` that have the fewest corrections any route
    can have (``certain``'s fewest), are feasible as flown and, with ``probability``, pass no
    unreliable point: no front route is longer (see the module's docstring). None when none
    of ``routes`` qualifies."""
    finite = np.flatnonzero(np.isfinite(certain.least))
    if not len(finite):
        return None
    fewest = int(finite[0])
    best = None
    for points in routes:
        points = tuple(int(i) for i in points)
        if len(points) - 2 != fewest or len(set(points)) != len(points):
            continue
        if probability and bool(np.any(scenario.unreliable[list(points)])):
            continue
        route = flown_route(scenario, points)
        if route.feasible and (best is None or route.length < best):
            best = float(route.length)
    return best


def ellipsoid(scenario: Scenario, bound: float) -> np.ndarray:
    """The points p with |AP| + |PB| <= ``bound`` (A and B among them), ascending."""
    xyz = scenario.xyz
    through = np.linalg.norm(xyz - xyz[scenario.start], axis=1)
    through += np.linalg.norm(xyz - xyz[scenario.end], axis=1)
    inside = through <= bound * (1.0 + _ROUNDING)
    inside[[scenario.start, scenario.end]] = True
    return np.flatnonzero(inside)


def large(scenario: Scenario) -> bool:
    """Whether ``scenario`` is large enough to focus (``FOCUS_FROM``)."""
    return scenario.n >= FOCUS_FROM


def focus(
    scenario: Scenario,
    certain: CertainFront | None,
    routes: Sequence[Sequence[int]],
    probability: bool,
) -> np.ndarray | None:
    """The points to search (indices of ``scenario``), or None to search them all: on maps of
    ``FOCUS_FROM`` points or more, and only where the ellipsoid holds at most half of them
    (elsewhere the bounds over all points cost about as much)."""
    if certain is None or not large(scenario):
        return None
    bound = front_bound(scenario, certain, routes, probability)
    if bound is None:
        return None
    inside = ellipsoid(scenario, bound)
    return inside if 2 * len(inside) <= scenario.n else None
