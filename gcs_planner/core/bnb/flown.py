"""Routes flown again under the scenario's leg model, independently of the search."""

from __future__ import annotations

import math
import sys

import numpy as np

from gcs_planner.core.route import Leg, Route, evaluate_route
from gcs_planner.geometry.airplane import AirplaneLeg
from gcs_planner.geometry.legs import FlownLeg, LegModel, path_angle_deg, scenario_leg_model
from gcs_planner.geometry.trajectory import route_trajectory
from gcs_planner.scenario.model import Scenario


def flown_route(
    scenario: Scenario, points: tuple[int, ...], model: LegModel | None = None
) -> Route:
    """Re-evaluate a route under the scenario's leg model (or ``model``), independently of the
    search: every leg flown again from the heading the previous one ended with."""
    R = scenario.params.turn_radius
    if model is not None and model.name == "bound":
        xyz = scenario.xyz[list(points)]
        bounds = [float(model.lower_bounds(a, b[None, :])[0]) for a, b in zip(xyz, xyz[1:])]
        return evaluate_route(scenario, points, [Leg(d) for d in bounds], turn_radius=R)
    legs = [flown_leg(leg) for leg in flown_route_legs(scenario, points, model)]
    return evaluate_route(scenario, points, legs, turn_radius=R)


def flown_route_legs(
    scenario: Scenario, points: tuple[int, ...], model: LegModel | None = None
) -> tuple[FlownLeg, ...]:
    """The legs of a route flown under the scenario's leg model (or ``model``), from the
    heading at A (free when none is given)."""
    heading = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)
    model = scenario_leg_model(scenario) if model is None else model
    R = scenario.params.turn_radius
    return route_trajectory(scenario.xyz[list(points)], R, heading, model).legs


def _compiled_flight(
    scenario: Scenario, points: tuple[int, ...], model: LegModel, *, compiled: bool = True
) -> list[float] | None:
    """The flown length of each leg of a route as ``flown_route`` flies it, the legs after the
    first with the model's compiled legs (within a few ulp; about 3 µs a leg instead of about
    260); None where that would load numba (only once a search has loaded it), where the
    model has no compiled legs or ``compiled`` is False. The first leg is ``flown_route``'s
    own (a free heading at A has its own rules), the heading carried from it."""
    fast = getattr(model, "compiled_lengths", None) if compiled else None
    if fast is None or "numba" not in sys.modules or len(points) < 3:
        return None
    xyz = scenario.xyz
    first = flown_route_legs(scenario, points[:2], model)[0]
    lengths = [first.length if first.reachable else math.inf]
    # (As ``route_trajectory``: after a leg that cannot be flown, the heading it started with.)
    # (A copy: the leg's heading is frozen, and a read-only array would be a second
    # specialisation of the airplane kernel to compile, besides the search's.)
    heading = np.array(first.heading_out if first.reachable else first.heading_in, float)
    for a, b in zip(points[1:], points[2:]):
        flown, headings = fast(xyz[a], heading, xyz[b][None, :])
        lengths.append(float(flown[0]))
        if math.isfinite(flown[0]):
            heading = headings[0]
    return lengths


def flown_leg(leg: FlownLeg) -> Leg:
    """The route table's view of a flown leg."""
    angle = path_angle_deg(leg)
    limit = None
    if isinstance(leg, AirplaneLeg):
        limit = leg.climb_limit_deg if angle > 0 else leg.descent_limit_deg
    return Leg(
        leg.length,
        leg.arc_length,
        leg.arc_angle,
        int(getattr(leg, "helix_turns", 0)),
        angle,
        limit,
    )
