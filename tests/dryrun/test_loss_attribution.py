"""Which lost runs the flight lost (gcs_planner/dryrun/run.py ``lost_by_the_flight``): a run is
lost by its corrections only where the plan itself, flown as planned with the same outcomes, is
lost too. Held against the exact probability model: summed over every outcome of a route's
unreliable points, weighted by its chance, the outcomes the plan survives make up exactly the
route's success probability (core/probability.py, an independent Markov chain over error
states); and a route certain to arrive is never lost by its corrections."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from support.enumeration import all_routes
from support.scenarios import tall_scenario

from gcs_planner.core.bnb import flown_route
from gcs_planner.core.probability import success_probability
from gcs_planner.dryrun.run import lost_by_the_flight

# The routes flown pass at most this many points between A and B: of the 4 or 5 points of a
# tall scenario, the routes through 4 or 5 are nearly all infeasible (6 % of the feasible ones
# over the 40 seeds below) yet are most of the routes to fly; through 2 or 3, 40 seeds give
# over a hundred feasible routes, some forty of them with two or more unreliable points.
MOST_POINTS = 3


def _routes(seed: int, first: int | None = None):
    """The feasible routes of a tall random scenario planned without a reserve (the
    probability model and the aircraft's limits then agree) through at most MOST_POINTS
    points, shortest chains first; only the ``first`` of them when given (the others are not
    flown)."""
    scenario = tall_scenario(seed, "airplane", 400.0, False).with_params(reserve=0.0)
    out = []
    shallow = itertools.takewhile(lambda r: len(r) <= MOST_POINTS + 2, all_routes(scenario))
    for points in shallow:
        route = flown_route(scenario, points)
        if route.feasible:
            out.append(route)
            if len(out) == first:
                break
    return scenario, out


def test_the_outcomes_the_plan_survives_sum_to_its_probability() -> None:
    checked = uncertain = 0
    for seed in range(40):
        scenario, routes = _routes(seed, first=40)
        p = scenario.params.p_success
        for route in routes:
            unreliable = [s.id for s in route.stops[1:-1] if s.unreliable]
            total = 0.0
            for k in range(len(unreliable) + 1):
                for failed in itertools.combinations(unreliable, k):
                    if not lost_by_the_flight(route, scenario.params, False, failed):
                        continue  # the plan is lost with these outcomes
                    total += p ** (len(unreliable) - k) * (1 - p) ** k
            legs = [s.leg for s in route.stops[1:]]
            want = success_probability(scenario, route.points, legs).probability
            assert total == pytest.approx(want, abs=1e-12), (seed, route.points)
            checked += 1
            uncertain += want < 1.0 - 1e-12
    assert checked >= 80 and uncertain >= 20, (checked, uncertain)


def test_a_certain_route_is_never_lost_by_its_corrections_a_miss_always_the_flights() -> None:
    seen = 0
    for seed in range(12):
        scenario, routes = _routes(seed)
        for route in routes:
            legs = [s.leg for s in route.stops[1:]]
            if success_probability(scenario, route.points, legs).probability < 1.0:
                continue
            unreliable = [s.id for s in route.stops[1:-1] if s.unreliable]
            rng = np.random.default_rng(seed)
            failed = [i for i in unreliable if rng.random() < 0.5]
            assert lost_by_the_flight(route, scenario.params, False, failed)
            seen += 1
    assert seen >= 5
    scenario, routes = _routes(0, first=5)
    assert all(lost_by_the_flight(r, scenario.params, True, []) for r in routes)
