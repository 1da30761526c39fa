"""The aircraft: a point-mass fixed wing at its airspeed, turning at most at its bank limit and
climbing or sinking at most at its flight-path-angle limits (gcs_planner.vehicle.VehicleProfile).

No wind, no roll or pitch dynamics: the bank and the climb rate the autopilot asks for are flown
at once, within the limits. So the aircraft never turns tighter than its turning radius
R = V^2 / (g tan phi) and never climbs steeper than its climb angle: the two limits the planner's
legs must respect, and the ones a dry run must be able to catch being broken.

A step integrates the horizontal motion exactly on the arc of constant turn rate, so a coarse
fixed step (0.5 s at 25 m/s: 12.5 m) flies a circle of radius R as a circle, not as a polygon.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from gcs_planner.vehicle import G, VehicleProfile

# With the angle limits at 90 degrees ("unlimited", the contest's model) the aircraft still cannot
# fly straight up: it keeps this much of its airspeed horizontal.
STEEPEST_DEG = 89.0


@dataclass(frozen=True)
class Envelope:
    """What the flight model enforces, derived from the profile at the current airspeed."""

    airspeed: float  # m/s
    bank_limit_deg: float  # 90 = turns of radius 0 (straight-leg plans)
    climb_rate: float  # m/s, > 0
    sink_rate: float  # m/s, > 0
    # rad/s; inf when the aircraft turns on the spot (turning radius 0). Derived, kept as a
    # field because the guidance reads it every step.
    max_turn_rate: float = field(init=False)

    def __post_init__(self) -> None:
        rate = math.inf
        if self.bank_limit_deg < 90.0:
            rate = G * math.tan(math.radians(self.bank_limit_deg)) / self.airspeed
        object.__setattr__(self, "max_turn_rate", rate)

    @property
    def min_radius(self) -> float:
        rate = self.max_turn_rate
        return 0.0 if math.isinf(rate) else self.airspeed / rate


def envelope_of(profile: VehicleProfile, airspeed: float | None = None) -> Envelope:
    """The profile's limits at ``airspeed`` (default its cruise airspeed). The bank limit is the
    bank that turns on the profile's radius at cruise: a faster aircraft turns wider."""
    v = float(airspeed or profile.cruise_airspeed)
    bank = profile.bank_angle if profile.turn_radius > 0 else 90.0
    climb = min(profile.max_climb_angle, STEEPEST_DEG)
    sink = min(profile.max_descent_angle, STEEPEST_DEG)
    return Envelope(v, bank, v * math.sin(math.radians(climb)), v * math.sin(math.radians(sink)))


@dataclass
class AircraftState:
    """Position (local frame, m: x east, y north, z up), course (rad, counter-clockwise from
    east), and what it flew last step: bank (deg, right wing down positive) and climb rate."""

    x: float
    y: float
    z: float
    course: float
    t: float = 0.0
    bank_deg: float = 0.0
    climb_rate: float = 0.0


def step(
    s: AircraftState, env: Envelope, turn_rate: float, climb_rate: float, dt: float
) -> AircraftState:
    """Fly ``dt`` seconds asking for ``turn_rate`` (rad/s, counter-clockwise positive) and
    ``climb_rate`` (m/s); both are clipped to the envelope. ``turn_rate`` may be inf for an
    aircraft without turn limit: the caller then sets the course itself."""
    vz = min(max(climb_rate, -env.sink_rate), env.climb_rate)
    vh = math.sqrt(max(env.airspeed * env.airspeed - vz * vz, 0.0))
    limit = env.max_turn_rate
    w = turn_rate if math.isinf(limit) else min(max(turn_rate, -limit), limit)
    if math.isinf(w) or abs(w) < 1e-9:
        w = 0.0 if math.isinf(w) else w
        x = s.x + vh * dt * math.cos(s.course)
        y = s.y + vh * dt * math.sin(s.course)
        course = s.course
    else:
        course = s.course + w * dt
        x = s.x + vh / w * (math.sin(course) - math.sin(s.course))
        y = s.y - vh / w * (math.cos(course) - math.cos(s.course))
    # Coordinated turn: tan(bank) = V w / g; a counter-clockwise turn is a left bank.
    bank = -math.degrees(math.atan(env.airspeed * w / G))
    return AircraftState(x, y, s.z + vz * dt, _wrap(course), s.t + dt, bank, vz)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi
