"""Routes flown by shared prefix (support/prefix_flight.py), which several exactness references
enumerate with, are ``bnb.flown_route``'s stop for stop: airplane legs with and without climb
limits, cs3d legs, a heading given at A, every simple route of each scenario."""

from __future__ import annotations

from support.enumeration import all_routes
from support.prefix_flight import PrefixFlights
from support.scenarios import climbing_scenario, turning_scenario

from gcs_planner.core.bnb import flown_route
from gcs_planner.core.route import Route


def _stops(route: Route) -> list[tuple]:
    return [
        (
            s.index,
            s.cumulative,
            s.v_flown,
            s.h_flown,
            s.within_limits,
            None if s.leg is None else s.leg.length,
        )  # fmt: skip
        for s in route.stops
    ]


def test_routes_flown_by_prefix_are_flown_route_stop_for_stop() -> None:
    scenarios = []
    for seed in range(3):
        scenarios.append(turning_scenario(seed, [200.0, 1500.0][seed % 2], max_points=5))
        scenarios.append(climbing_scenario(seed, max_points=5))
    scenarios.append(turning_scenario(7, 800.0, max_points=5).with_vehicle(leg_model="cs3d"))
    scenarios.append(
        turning_scenario(8, 800.0, max_points=5).with_vehicle(heading_at_a=(0.0, 1.0, 0.0))
    )
    compared = feasible = 0
    for x, scenario in enumerate(scenarios):
        flights = PrefixFlights(scenario)
        for points in all_routes(scenario):
            got, want = flights.route(points), flown_route(scenario, points)
            assert got.points == want.points and _stops(got) == _stops(want), (x, points)
            compared += 1
            feasible += want.feasible
    assert compared >= 500 and feasible >= 20, (compared, feasible)
