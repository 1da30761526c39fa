"""The bounds of the branch and bound against enumeration and independent flights: the length
still to fly of a continuation that keeps most of a partial route's mass (``failure_bounds``),
the relaxation front's floor under every route by corrections and probability (``Ceiling``),
and the leg bounds that know the cone of headings at a point (``pair_bounds``)."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest
from support.enumeration import all_routes, assert_front_equals_enumeration
from support.prefix_flight import PrefixFlights
from support.scenarios import climbing_scenario, turning_scenario, uncertain_straight_scenario

from gcs_planner.core.bnb import PROB_EPS, Ceiling, Options
from gcs_planner.core.bnb.context import _Context
from gcs_planner.core.bnb.front import _relaxed
from gcs_planner.core.budget import Budget
from gcs_planner.core.failure_bounds import failure_bounds
from gcs_planner.core.pair_bounds import cone_half_angles, pair_leg_bounds
from gcs_planner.core.probability import propagate
from gcs_planner.core.reach import build_reach_graph
from gcs_planner.geometry.airplane import airplane_leg
from gcs_planner.geometry.legs import AirplaneLegs
from gcs_planner.scenario.model import Kind, Scenario


def scenarios(seeds: range = range(20)):
    """Straight legs with many unreliable points, turns of several radii, and airplane legs
    with large altitude differences (helices) under several climb limits (each at most 4
    correction points: 65 routes each to fly, not 326; the same draws)."""
    for seed in seeds:
        for family in range(3):
            yield _scenario(family, seed)


@functools.cache
def _scenario(family: int, seed: int) -> Scenario:
    """One scenario of ``scenarios``, made once per test process: the tests below fly the routes
    of the same ones (each route flown once, ``prefixes``)."""
    if family == 0:
        return uncertain_straight_scenario(seed, max_points=4)
    if family == 1:
        return turning_scenario(seed, [200.0, 1500.0, 4000.0][seed % 3], max_points=4)
    return climbing_scenario(seed, max_points=4)


# The routes flown of each scenario of ``_scenario`` (by its id: they live as long as the process).
_FLIGHTS: dict[int, tuple[Scenario, PrefixFlights, dict]] = {}


def prefixes(scenario, points):
    """Per correction point of a route: (position, length so far, error states after it), and
    the route's length and probability, all from the route flown independently."""
    if id(scenario) not in _FLIGHTS:
        _FLIGHTS[id(scenario)] = (scenario, PrefixFlights(scenario), {})
    kept, flights, routes = _FLIGHTS[id(scenario)]
    assert kept is scenario
    if points not in routes:
        routes[points] = flights.route(points)
    route = routes[points]
    kind = [Kind(int(c)) for c in scenario.kind]
    states = {(0.0, 0.0): 1.0}
    length = 0.0
    out = []
    for i, stop in enumerate(route.stops[1:], start=1):
        leg = stop.leg.length
        if not np.isfinite(leg):
            return [], route.length, 0.0
        j = points[i]
        states, _ = propagate(states, leg, kind[j], bool(scenario.unreliable[j]), scenario.params)
        length += leg
        if not states:
            return [], route.length, 0.0
        if i < len(points) - 1:
            out.append((i, length, dict(states)))
    return out, length, min(1.0, sum(states.values()))


def test_failure_bounds_never_exceed_a_continuation_that_keeps_that_much_mass() -> None:
    checked = forced = 0
    for scenario in scenarios():
        graph = build_reach_graph(scenario)
        bounds = failure_bounds(scenario, graph)
        if bounds is None:
            continue
        for points in all_routes(scenario):
            steps, total, probability = prefixes(scenario, points)
            if probability <= 0:
                continue
            for i, length, states in steps:
                j = points[i]
                mass = sum(states.values())
                loss = mass - probability
                rest = total - length
                more = len(points) - 2 - i  # corrections after j
                # the tightest gap this continuation satisfies, and looser ones
                for gap in (loss + 1e-7, loss + 0.05, loss + 0.3, mass):
                    if gap <= loss:
                        continue
                    row = bounds.bound(j, states, gap)
                    assert row is not None, (points, i, gap)
                    assert row[min(more, len(row) - 1)] <= rest + 1e-6, (points, i, gap)
                    checked += 1
                    forced += any(bounds.forced(w, gap) > 0 for w in states.values())
    print(checked, forced)
    assert checked >= 1_000 and forced >= 100, (checked, forced)


def test_the_relaxation_front_floors_every_route_by_corrections_and_probability() -> None:
    checked = 0
    for scenario in scenarios(range(30)):  # of at most 4 points: more of them
        if scenario.params.turn_radius <= 0:
            continue
        ctx = _Context(scenario, True, None)
        floor = _relaxed(ctx.relaxed(), Budget(None), ())
        assert floor.optimal
        ceiling = Ceiling(floor.front, ctx.kmax)
        levels = sorted({0.0, *(f.probability for f in floor.front)})
        for points in all_routes(scenario):
            _, length, probability = prefixes(scenario, points)
            if probability <= 0:
                continue
            c = len(points) - 2
            for lo in levels:
                if probability > lo + PROB_EPS:
                    assert ceiling.least_above(lo)[c] <= length + 1e-6, (points, lo)
                    checked += 1
            # nothing is more likely than the relaxation's likeliest route
            assert probability <= max(f.probability for f in floor.front) + PROB_EPS
    print(checked)
    assert checked >= 200, checked


def test_arrival_headings_lie_in_the_cone_and_pair_bounds_never_exceed_a_flown_leg() -> None:
    """The heading an airplane leg arrives with is within asin(2R / h) of its horizontal chord,
    whatever it started with; and lb(i, j, t) is no longer than the leg j -> t flown from any
    such heading — steep legs (helices), several radii and climb limits."""
    rng = np.random.default_rng(7)
    checked = helices = 0
    for _ in range(120):
        radius = float(rng.choice([50.0, 200.0, 800.0]))
        climb, descent = float(rng.choice([8.0, 15.0, 25.0, 90.0])), float(rng.uniform(5, 30))
        model = AirplaneLegs(radius, climb, descent)
        pts = rng.uniform([-6_000, -6_000, -2_500], [6_000, 6_000, 2_500], (3, 3))
        i, j, t = pts
        psi = rng.uniform(0, 2 * np.pi, 32)
        starts = np.column_stack([np.cos(psi), np.sin(psi), np.zeros(32)])
        arrive = [airplane_leg(i, u, j, radius, climb, descent) for u in starts]
        chord = np.arctan2(j[1] - i[1], j[0] - i[0])
        cone = cone_half_angles(np.array([np.hypot(*(j - i)[:2])]), radius)[0]
        bound = pair_leg_bounds(
            pts,
            np.array([0]),
            np.array([1]),
            np.array([2]),
            model,
            model.lower_bounds(j, t[None, :]),
        )[0]
        for leg in arrive:
            if not np.isfinite(leg.length):
                continue
            heading = leg.heading_out
            off = abs((np.arctan2(heading[1], heading[0]) - chord + np.pi) % (2 * np.pi) - np.pi)
            assert off <= cone + 1e-9
            onward = airplane_leg(j, heading, t, radius, climb, descent)
            assert bound <= onward.length + 1e-6
            checked += 1
            helices += onward.helix_turns > 0
    assert checked >= 2_000 and helices >= 50, (checked, helices)


@pytest.mark.parametrize("make", [climbing_scenario, turning_scenario])
def test_fronts_with_the_failure_bounds_from_the_first_label_equal_enumeration(make) -> None:
    """The search makes the failure bounds only once it has expanded many labels, which small
    scenarios never reach: here it makes them at once, and the fronts must stay exact."""
    at_once = Options(failure_bounds_per_arc=0.0)
    nonempty = 0
    for seed in range(24):
        # at most 4 correction points (65 routes to fly, not 326), the same draws
        scenario = (
            make(seed, max_points=4)
            if make is climbing_scenario
            else make(seed, [200.0, 1500.0][seed % 2], max_points=4)
        )
        _, want = assert_front_equals_enumeration(scenario, True, seed, at_once)
        nonempty += bool(want)
    assert nonempty >= 8


def test_fronts_with_a_heading_at_a_equal_enumeration() -> None:
    """A heading given at A: the first leg turns, and the pair relaxation starts without an arc."""
    nonempty = 0
    for seed in range(24):
        # At most 4 correction points (65 routes to fly, not 326): 19 fronts of 24 nonempty,
        # as with 5.
        scenario = climbing_scenario(seed, max_points=4)
        psi = 0.7 * seed
        scenario = dataclasses.replace(scenario, heading_at_a=(np.cos(psi), np.sin(psi), 0.0))
        _, want = assert_front_equals_enumeration(scenario, True, seed)
        nonempty += bool(want)
    assert nonempty >= 8
