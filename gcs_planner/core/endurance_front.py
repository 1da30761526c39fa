"""The endurance as a constraint of the front (docs/model.md, "Endurance in the plan"): only
routes whose flight time in the design wind (core/flight_time.py) is within
``scenario.endurance``; the proof and the search are core/constrained_front.py's.

Flight time is a resource along a route, carried by the search as the seconds flown so far. A
prefix is dropped when those plus the least time from its last point to B
(``flight_time.seconds_to_b``: each leg is at least its chord) exceed the endurance; when that
holds at A no route is within it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import lru_cache

from gcs_planner.core.constrained_front import Leg
from gcs_planner.core.flight_time import ground_speeds, route_minutes, seconds_to_b
from gcs_planner.core.route import Route
from gcs_planner.scenario.model import Scenario

# Rows of ground speeds (one per origin of a leg) the search keeps: enough for the origins of
# the routes it is extending, a bounded memory on maps of thousands of points.
_ROWS_KEPT = 256
# Relative rounding of a sum of leg times (a few ulp per leg): the bound's margin.
_ROUNDING = 1e-12


class EnduranceLimit:
    """Flight time in the design wind within ``scenario.endurance`` minutes."""

    every_outcome = False

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.limit_min = float(scenario.endurance)  # type: ignore[arg-type]
        self.limit_s = self.limit_min * 60.0
        self.to_b = seconds_to_b(scenario)
        self.least_min = float(self.to_b[scenario.start]) / 60.0
        self.figures = {"endurance_min": self.limit_min, "least_flight_min": self.least_min}
        xyz = scenario.xyz
        self._speeds = lru_cache(maxsize=_ROWS_KEPT)(lambda i: ground_speeds(scenario, xyz[i], xyz))

    def passable(self, point: int) -> bool:
        return bool(self.to_b[point] <= self.limit_s)

    def admits(self, leg: Leg, carried: float) -> float | None:
        """The seconds flown at the leg's end, None when even the least time from there to B
        takes them beyond the endurance (or the wind leaves the leg no ground speed)."""
        vg = float(self._speeds(leg.origin)[leg.target])
        if not vg > 0.0:
            return None
        seconds = carried + leg.flown / vg
        if leg.target == self.scenario.end:
            # B: the route's own test (``route_minutes`` within the minutes), so that a route
            # flying exactly the endurance is decided as the plan's check decides it.
            return seconds if seconds / 60.0 <= self.limit_min else None
        # The bound only prunes: a margin of float rounding keeps it from dropping such a route.
        bound = seconds + self.to_b[leg.target]
        return seconds if bound <= self.limit_s * (1.0 + _ROUNDING) else None

    def route_keeps(self, route: Route) -> bool:
        return route_minutes(self.scenario, route) <= self.limit_min

    def refusal(self) -> str | None:
        if self.least_min <= self.limit_min:
            return None
        return (
            f"no route within the endurance of {self.limit_min:g} min: every route needs at "
            f"least {minutes_text(self.least_min)} of flight in the design wind (the chords to "
            'B at the ground speed along each; docs/model.md, "Endurance in the plan")'
        )

    def phrase(self) -> str:
        return f"within the endurance of {self.limit_min:g} min in the design wind"

    def front_keeps(self, routes: Sequence[Route]) -> str:
        longest = max(route_minutes(self.scenario, r) for r in routes)
        return (
            f"; every front route flies within the endurance of {self.limit_min:g} min in the "
            f"design wind (the longest {minutes_text(longest)}), so this is the front within it"
        )

    def why_none(self, routes: Sequence[Route]) -> str:
        quickest = min(route_minutes(self.scenario, r) for r in routes)
        return (
            f"the quickest route of the front of all routes needs {minutes_text(quickest)} of "
            f"flight in the design wind, and no route needs less than "
            f"{minutes_text(self.least_min)}"
        )


def endurance_limit(scenario: Scenario) -> EnduranceLimit | None:
    """The scenario's endurance as a constraint of the front; None without one."""
    return None if scenario.endurance is None else EnduranceLimit(scenario)


def minutes_text(minutes: float) -> str:
    """Minutes as the plan says them: '378 min (6.3 h)'."""
    if not math.isfinite(minutes):
        return "forever (the design wind is at least the airspeed)"
    return f"{minutes:.0f} min ({minutes / 60:.1f} h)" if minutes >= 90 else f"{minutes:.1f} min"
