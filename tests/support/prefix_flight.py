"""Every simple route of a scenario flown as ``bnb.flown_route`` flies it, each leg once for all
the routes that share the partial route before it (a route's legs depend only on the points
before them): the same Route, for brute-force references over every simple route."""

from __future__ import annotations

import math
from collections.abc import Iterator

from gcs_planner.core.bnb import flown_leg, flown_route, flown_route_legs
from gcs_planner.core.route import Route, evaluate_route
from gcs_planner.geometry.dubins import COINCIDENT_M
from gcs_planner.geometry.legs import FlownLeg, scenario_leg_model
from gcs_planner.scenario.model import Scenario

from .enumeration import all_routes, enumerate_fronts


class PrefixFlights:
    """``route(points)`` equals ``flown_route(scenario, points)``: the first leg flown as a route
    of two points flies it (a free heading at A has its own rules), each later leg from the
    heading the one before ended with (its start heading where it could not be flown, as
    ``route_trajectory`` carries on), memoised by the partial route it follows."""

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.model = scenario_leg_model(scenario)
        self.legs: dict[tuple[int, ...], tuple[FlownLeg, ...]] = {}

    def _legs(self, points: tuple[int, ...]) -> tuple[FlownLeg, ...]:
        got = self.legs.get(points)
        if got is None:
            if len(points) == 2:
                got = flown_route_legs(self.scenario, points)
            else:
                before = self._legs(points[:-1])
                prev = before[-1]
                heading = prev.heading_out if prev.reachable else prev.heading_in
                xyz = self.scenario.xyz
                got = (*before, self.model.leg(xyz[points[-2]], heading, xyz[points[-1]]))
            self.legs[points] = got
        return got

    def route(self, points: tuple[int, ...]) -> Route:
        xyz = self.scenario.xyz
        # A free heading at A on top of the next point looks further along the route.
        if math.dist(xyz[points[0]], xyz[points[1]]) <= COINCIDENT_M:
            return flown_route(self.scenario, points)
        legs = [flown_leg(leg) for leg in self._legs(tuple(points))]
        return evaluate_route(
            self.scenario, points, legs, turn_radius=self.scenario.params.turn_radius
        )


def every_route_flown(scenario: Scenario) -> Iterator[tuple[tuple[int, ...], Route]]:
    """(points, ``flown_route``) of every simple route from A to B, shortest chains first."""
    flights = PrefixFlights(scenario)
    for points in all_routes(scenario):
        yield points, flights.route(points)


def enumerated_fronts(scenario: Scenario) -> dict:
    """``enumeration.enumerate_fronts(scenario)``, every simple route flown by prefix."""
    return enumerate_fronts(scenario, every_route_flown(scenario))
