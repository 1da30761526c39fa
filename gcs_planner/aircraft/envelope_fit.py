"""Whether a plan's legs fit the aircraft's envelope in the wind it will be flown in (issue 32).

The planner holds its legs to a design wind W0 (vehicle.DerivedEnvelope: every ground speed up
to V + W0). A dry run may fly the plan in a stronger wind W (``--design-wind 0 --wind 5``): then
some legs need more than the aircraft can give. Before the flight, each leg is checked against
the same closed-form envelope with the flown W, leg by leg at the true airspeed V of the leg's
own highest point (ISA; the planner takes the scenario's highest point, so a plan for W0 >= W
always fits):

* climb (descent) angle <= atan(climb (sink) rate / (V + W)): a tailwind makes the ground
  slope the rate can hold shallower;
* the turning radius of every leg that turns (its arc or its helix) >= (V + W)^2 / (g tan
  phi): flown downwind at the roll limit the ground track is no tighter than that;
* where the plan runs straight over a landmark for the autopilot's settle distance (the run-in
  and run-out derived from the autopilot), the straight into and out of each correction point
  >= the autopilot's settle distance at V + W.

The wind is taken from any direction (V + W), as the planner does: a flight that arrives in
the directions it drew has not flown the others. A flown wind of a stated direction checks each
leg's climb and descent along its own track instead (the fastest ground speed over its
headings, ``airplane.track_factor``; a helix flies every heading), as a plan for a design wind
of a stated direction holds them; the radius and the runs stay checked at V + W. Gusts are not
in the envelope (the design wind is steady); the flight reports what they do.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from gcs_planner.aircraft.profile import G, tas_from_eas
from gcs_planner.geometry.airplane import AirplaneLeg, track_factor, wind_towards
from gcs_planner.geometry.legs import path_angle_deg
from gcs_planner.geometry.trajectory import scenario_trajectory
from gcs_planner.scenario.model import Kind, Scenario

# A leg at its limit in the design wind is at it to the last bits of a float: the search
# compares the same numbers, the check recomputes them through another path.
RELATIVE_SLACK = 1e-9


@dataclass(frozen=True)
class LegShortfall:
    """One leg of a route that needs more than the aircraft can give in the flown wind."""

    leg: int  # 1-based: leg k flies from route point k-1 to route point k
    start: str  # point ids
    end: str
    limit: str  # "climb angle", "descent angle", "turning radius", "run-in", "run-out"
    needs: float  # what the leg needs (degrees or metres)
    can: float  # what the aircraft can do in the wind (degrees, or metres it needs at least)
    unit: str  # "deg" or "m"
    ground_speed: float  # V + W at the leg's highest point, m/s
    why: str  # how ``can`` was derived, with the numbers

    def describe(self) -> str:
        return f"leg {self.leg} ({self.start} -> {self.end}): {self.why}"


def legs_outside_envelope(
    scenario: Scenario,
    points: Sequence[int],
    wind: float,
    settle_distance: Callable[[float], float] | None = None,
    wind_from: float | None = None,
) -> list[LegShortfall]:
    """Every (leg, limit) of the route through ``points`` (scenario indices, A..B) that does not
    fit the envelope of ``scenario.envelope``'s aircraft in a ``wind`` of that many m/s from any
    direction; empty when the scenario states no aircraft in the autopilot's terms (nothing to
    derive the envelope from: the flight is the only judge).

    ``settle_distance(ground_speed)``: the flown autopilot's straight-line settle distance; the
    run-in and run-out are checked only when the plan derived them from the autopilot (a user
    who states ``--approach``/``--departure`` has said what the aircraft needs).
    ``wind_from``: the flown wind's direction (degrees it blows from), None when the flight
    draws one per run (then from any direction)."""
    env = scenario.envelope
    if env is None:
        return []
    alt0 = scenario.origin.alt if scenario.origin is not None else 0.0
    ids = [str(scenario.ids[p]) for p in points]
    kinds = [Kind(int(scenario.kind[p])) for p in points]
    landmark = (Kind.V, Kind.H)
    runs = settle_distance is not None and env.runs_source.startswith("derived")
    tan_bank = math.tan(math.radians(env.bank_deg)) if env.bank_deg > 0 else 0.0
    out: list[LegShortfall] = []
    legs = scenario_trajectory(scenario, points).legs
    for k, leg in enumerate(legs, start=1):
        top = max(float(leg.start[2]), float(leg.end[2])) + alt0
        tas = tas_from_eas(env.eas, top)
        vg = tas + wind
        found: list[tuple[str, float, float, str, str]] = []  # limit, needs, can, unit, why
        short = found.append

        speed = f"{tas:.2f} m/s TAS at {top:.0f} m + {wind:g} m/s wind"
        angle = path_angle_deg(leg)
        vg_climb, over = vg, f"({speed})"
        if wind_from is not None and wind > 0 and isinstance(leg, AirplaneLeg):
            vg_climb = vg / _track_factor(leg, tas, wind, wind_from)
            over = (
                f"{vg_climb:.2f} m/s, the fastest along its track ({speed} from {wind_from:g} deg)"
            )
        for sign, limit, rate in ((1, "climb angle", env.climb_rate),
                                  (-1, "descent angle", env.sink_rate)):  # fmt: skip
            if math.isinf(rate) or sign * angle <= 0:
                continue
            can = math.degrees(math.atan2(rate, vg_climb))
            if sign * angle > can * (1 + RELATIVE_SLACK):
                needed_rate = vg_climb * math.tan(math.radians(sign * angle))
                verb = "climbs" if sign > 0 else "descends"
                short((limit, sign * angle, can, "deg",
                      f"{verb} at {sign * angle:.3f} deg, {needed_rate:.2f} m/s at "
                      f"{vg_climb:.2f} m/s over the ground; the aircraft {verb} at {rate:g} m/s: "
                      f"atan({rate:g} / {over}) = {can:.3f} deg"))  # fmt: skip
        if tan_bank > 0 and leg.radius > 0 and _turns(leg):
            need_r = vg * vg / (G * tan_bank)
            if leg.radius < need_r * (1 - RELATIVE_SLACK):
                short(("turning radius", leg.radius, need_r, "m",
                      f"turns on {leg.radius:.2f} m; at {env.bank_deg:g} deg bank the aircraft "
                      f"turns on (V + W)^2 / (g tan phi) = ({speed})^2 / (g tan "
                      f"{env.bank_deg:g}) = {need_r:.2f} m"))  # fmt: skip
        if runs:
            assert settle_distance is not None
            need_s = settle_distance(vg)
            ends = (
                ("run-in", kinds[k], _straight_in(leg), "into", ids[k]),
                ("run-out", kinds[k - 1], _straight_out(leg), "out of", ids[k - 1]),
            )
            for limit, kind, straight, way, point in ends:
                if kind in landmark and straight < need_s * (1 - RELATIVE_SLACK):
                    short((limit, straight, need_s, "m",
                           f"flies {straight:.2f} m straight {way} {kind.name} point {point}; "
                           f"the autopilot settles on a line in {need_s:.2f} m at {vg:.2f} m/s "
                           f"({speed})"))  # fmt: skip
        out += [LegShortfall(k, ids[k - 1], ids[k], *f[:4], vg, f[4]) for f in found]
    return out


def _track_factor(leg: AirplaneLeg, tas: float, wind: float, wind_from: float) -> float:
    """(V + W) / the fastest ground speed over the leg's headings (1 with a helix: it flies
    them all)."""
    if leg.helix_turns > 0:
        return 1.0
    u = np.asarray(leg.heading_in, dtype=float)[None, :2]
    n = np.zeros((1, 2)) if leg.normal is None else np.asarray(leg.normal, float)[None, :2]
    phi = np.array([leg.arc_angle if leg.normal is not None else 0.0])
    toward = wind_towards(wind, wind_from)
    return float(track_factor(u, n, phi, np.array([tas]), toward)[0])


def _turns(leg: object) -> bool:
    arc = float(getattr(leg, "arc_angle", 0.0))
    return getattr(leg, "normal", None) is not None and (
        arc > 0 or int(getattr(leg, "helix_turns", 0)) > 0
    )


def _straight_in(leg: object) -> float:
    """Horizontal metres flown straight into the leg's end (the whole leg when it never turns)."""
    if isinstance(leg, AirplaneLeg):
        return leg.straight_horizontal if _turns(leg) else leg.horizontal_length
    return float(leg.straight_length)  # type: ignore[attr-defined]


def _straight_out(leg: object) -> float:
    """Horizontal metres flown straight on from the leg's start before it turns."""
    if isinstance(leg, AirplaneLeg):
        return leg.run_out if _turns(leg) else leg.horizontal_length
    return 0.0 if _turns(leg) else float(leg.length)  # type: ignore[attr-defined]
