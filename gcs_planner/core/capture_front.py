"""The captures in a design turbulence as a constraint of the front (docs/model.md, "Turbulence
in the plan"): only routes at each of whose V, H and B points the worst error on arrival over
the correction outcomes, with the point's vertical allowance on the vertical error, plus the
tracking allowance, fits the capture radius (the condition of
:func:`gcs_planner.core.capture.capture_check`; a point no outcome that can happen reaches
within its limits does not fit). The proof and the search are core/constrained_front.py's.

Whether a capture fits depends only on the route up to that point, so a prefix whose capture
does not fit has no extension that fits; the search carries every correction outcome (a
dominating partial route may carry one that does not fit). A point whose allowance alone (no
error at all) exceeds the capture radius is never a capture that fits; when that holds of B,
no route fits.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from gcs_planner.aircraft.profile import TRACKING_ALLOWANCE_M
from gcs_planner.core.constrained_front import Leg
from gcs_planner.core.probability import State, propagate
from gcs_planner.core.route import Route
from gcs_planner.scenario.model import Kind, Scenario

CAPTURED = (Kind.V, Kind.H, Kind.B)


def arrival_fits(scenario: Scenario, point: int, arrived: Mapping[State, float]) -> bool:
    """Whether every error state ``arrived`` at ``point`` (metres flown since each reset, the
    states within its limits) passes within its capture radius with the point's vertical
    allowance and the tracking allowance (true at points that capture nothing)."""
    vertical = scenario.capture_vertical
    if vertical is None or Kind(int(scenario.kind[point])) not in CAPTURED:
        return True
    d, unit = scenario.params.delta, scenario.error_unit
    z = vertical[point] / unit
    # The arithmetic of capture_check, so that a boundary case is decided identically.
    worst = max(math.hypot(v * d + z, h * d) for v, h in arrived) * unit
    return not worst + TRACKING_ALLOWANCE_M > scenario.capture_radius


def route_fits(scenario: Scenario, route: Route) -> bool:
    """Whether every capture of ``route`` fits: at each point, over the correction outcomes
    that can happen and arrive within its limits (none arriving: it does not fit), the
    condition of :func:`arrival_fits`, the outcomes those of the probability model."""
    params = scenario.params
    states: dict[State, float] = {scenario.initial_errors: 1.0}
    for stop in route.stops[1:]:
        leg = 0.0 if stop.leg is None else stop.leg.length
        top_v, top_h = params.limits_m(stop.kind)
        arrived = [(v + leg, h + leg) for v, h in states]
        arrived = [(v, h) for v, h in arrived if v <= top_v and h <= top_h]
        point = scenario.index_of(stop.id)
        if not arrived or not arrival_fits(scenario, point, dict.fromkeys(arrived, 0.0)):
            return False
        states, _ = propagate(states, leg, stop.kind, stop.unreliable, params)
    return True


def _may_fit(scenario: Scenario, point: int) -> bool:
    """Whether a capture at ``point`` fits with no error at all."""
    return arrival_fits(scenario, point, {(0.0, 0.0): 1.0})


class CapturesFit:
    """Every capture of the route fits in the design turbulence (``arrival_fits`` over every
    correction outcome arriving within the point's limits)."""

    every_outcome = True

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.figures: dict[str, float] = {}
        self.vertical = scenario.capture_vertical or ()
        self.room = (
            f"the capture radius {scenario.capture_radius:g} m less the tracking allowance "
            f"{TRACKING_ALLOWANCE_M:g} m"
        )

    def passable(self, point: int) -> bool:
        return point == self.scenario.end or _may_fit(self.scenario, point)

    def admits(self, leg: Leg, carried: float) -> float | None:
        """0 when every outcome arriving at the leg's end fits its capture, else None."""
        return 0.0 if arrival_fits(self.scenario, leg.target, dict.fromkeys(leg.arrived)) else None

    def route_keeps(self, route: Route) -> bool:
        return route_fits(self.scenario, route)

    def refusal(self) -> str | None:
        end = self.scenario.end
        if _may_fit(self.scenario, end):
            return None
        return (
            f"no route fits its captures in the design turbulence: B's vertical allowance "
            f"{self.vertical[end]:.2f} m alone exceeds {self.room} "
            '(docs/model.md, "Turbulence in the plan")'
        )

    def phrase(self) -> str:
        return "whose every capture fits in the design turbulence"

    def front_keeps(self, routes: Sequence[Route]) -> str:
        return (
            "; every capture of every front route fits in the design turbulence, so this is "
            "the front of the routes whose captures fit"
        )

    def why_none(self, routes: Sequence[Route]) -> str:
        worst = max(self.vertical, default=0.0)
        return (
            f"no route fits its captures in the design turbulence: the vertical allowances, up "
            f"to {worst:.2f} m, leave too little of {self.room} for the INS error on arrival "
            '(docs/model.md, "Turbulence in the plan")'
        )


def captures_fit(scenario: Scenario) -> CapturesFit | None:
    """The captures in the scenario's design turbulence as a constraint of the front; None
    without one."""
    return None if scenario.capture_vertical is None else CapturesFit(scenario)
