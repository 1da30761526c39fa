"""The aircraft: a point-mass fixed wing flying through a moving air mass.

It holds an equivalent airspeed (EAS, what both autopilots hold: ArduPlane AIRSPEED_CRUISE, PX4
FW_AIRSPD_TRIM) and so flies through the air at the true airspeed TAS = EAS * EAS2TAS(altitude)
(sim/atmosphere.py, ISA). Its heading is where its nose points in the air; its course is where
it goes over the ground: the air velocity plus the wind (sim/wind.py). The autopilot asks for a
lateral acceleration (L1 and npfg both compute one from the ground velocity) and a climb rate;
the aircraft flies the bank atan(a / g), clipped to the autopilot's roll limit (ArduPlane
ROLL_LIMIT_DEG, PX4 FW_R_LIM), which turns its heading at g tan(bank) / TAS, and the climb rate
clipped to the autopilot's climb and sink rates (ArduPlane TECS_CLMB_MAX / TECS_SINK_MAX, PX4
in missions FW_T_CLMB_R_SP / FW_T_SINK_R_SP). No roll or pitch dynamics: what is asked is flown
at once, within those limits.

A step integrates the air-relative motion exactly on the arc of constant heading rate and adds
the wind's drift over the step, so a coarse fixed step (0.5 s at 25 m/s: 12.5 m) flies a circle
in still air as a circle, and its trochoid in a steady wind as the trochoid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs_planner.vehicle import G

# With unlimited climb (the contest's model) the aircraft still cannot fly straight up: it keeps
# this much of its airspeed horizontal.
STEEPEST_DEG = 89.0


@dataclass(frozen=True)
class Envelope:
    """What the flight model enforces: the autopilot's limits at the current airspeed."""

    airspeed: float  # m/s, equivalent (EAS)
    bank_limit_deg: float  # >= 90: turns on the spot (straight-leg plans, R = 0)
    climb_rate: float  # m/s, > 0
    sink_rate: float  # m/s, > 0

    @property
    def free_turn(self) -> bool:
        return self.bank_limit_deg >= 90.0

    @property
    def max_lateral_accel(self) -> float:
        return math.inf if self.free_turn else G * math.tan(math.radians(self.bank_limit_deg))

    def min_radius(self, tas: float | None = None) -> float:
        """The tightest circle through the air at the roll limit, at ``tas`` (default EAS)."""
        if self.free_turn:
            return 0.0
        v = self.airspeed if tas is None else tas
        return v * v / self.max_lateral_accel


@dataclass
class AircraftState:
    """Position (local frame, m: x east, y north, z up), heading (through the air) and course
    (over the ground), both rad counter-clockwise from east, and what it flew last step: bank
    (deg, right wing down positive), climb rate, true airspeed and ground speed."""

    x: float
    y: float
    z: float
    course: float
    t: float = 0.0
    bank_deg: float = 0.0
    climb_rate: float = 0.0
    heading: float | None = None
    tas: float = 0.0
    ground_speed: float = 0.0

    def __post_init__(self) -> None:
        if self.heading is None:
            self.heading = self.course


def step(
    s: AircraftState,
    env: Envelope,
    lateral_accel: float,
    climb_rate: float,
    dt: float,
    wind: tuple[float, float] = (0.0, 0.0),
    eas2tas: float = 1.0,
    heading: float | None = None,
) -> AircraftState:
    """Fly ``dt`` seconds asking for ``lateral_accel`` (m/s^2, positive to the left: a
    counter-clockwise turn) and ``climb_rate`` (m/s), both clipped to the envelope, through air
    moving at ``wind`` (east, north m/s) at EAS2TAS ``eas2tas``. An aircraft without a turn
    limit (``env.free_turn``) takes ``heading`` as given instead."""
    v = env.airspeed * eas2tas
    vz = min(max(climb_rate, -env.sink_rate), env.climb_rate)
    vh = math.sqrt(max(v * v - vz * vz, 0.0))
    psi0 = s.heading if s.heading is not None else s.course
    if env.free_turn:
        a = 0.0
        psi0 = psi0 if heading is None else heading
        w = 0.0
    else:
        limit = env.max_lateral_accel
        a = min(max(lateral_accel, -limit), limit)
        w = a / v  # g tan(bank) / TAS with tan(bank) = a / g
    wx, wy = wind
    if abs(w) < 1e-9:
        psi1 = psi0
        dx = vh * dt * math.cos(psi0)
        dy = vh * dt * math.sin(psi0)
    else:
        psi1 = psi0 + w * dt
        dx = vh / w * (math.sin(psi1) - math.sin(psi0))
        dy = -vh / w * (math.cos(psi1) - math.cos(psi0))
    gx, gy = vh * math.cos(psi1) + wx, vh * math.sin(psi1) + wy
    bank = -math.degrees(math.atan(a / G))  # a counter-clockwise turn is a left bank
    return AircraftState(
        s.x + dx + wx * dt,
        s.y + dy + wy * dt,
        s.z + vz * dt,
        math.atan2(gy, gx),
        s.t + dt,
        bank,
        vz,
        _wrap(psi1),
        v,
        math.hypot(gx, gy),
    )


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


# A turn entered as a real aircraft enters it (issue 31: JSBSim's c172r under the same inner
# loops reaches 42 of 45 degrees of bank in about 2 s): the bank follows the one asked as a
# first-order lag of ROLL_TAU_S, at most ROLL_RATE_DEG_S.
ROLL_TAU_S = 0.8
ROLL_RATE_DEG_S = 70.0
ROLL_SUBSTEP_S = 0.05


class RollLagPointMass:
    """The point mass whose bank lags the one asked (an airframe for sim/navigators/base.py).
    The bank is part of the state, so a step can be flown again from any state it returned
    (``exact``); each step is flown in substeps of at most ROLL_SUBSTEP_S, each an exact arc at
    the bank reached there. An aircraft without a turn limit turns on the spot as before."""

    exact = True

    def __init__(self, tau: float = ROLL_TAU_S, rate_deg_s: float = ROLL_RATE_DEG_S) -> None:
        self.tau = tau
        self.rate = rate_deg_s

    def step(
        self,
        s: AircraftState,
        env: Envelope,
        lateral_accel: float,
        climb_rate: float,
        dt: float,
        wind: tuple[float, float] = (0.0, 0.0),
        eas2tas: float = 1.0,
        heading: float | None = None,
    ) -> AircraftState:
        if env.free_turn:
            return step(s, env, lateral_accel, climb_rate, dt, wind, eas2tas, heading)
        limit = env.bank_limit_deg
        asked = min(max(-math.degrees(math.atan(lateral_accel / G)), -limit), limit)
        n = max(1, math.ceil(dt / ROLL_SUBSTEP_S - 1e-9))
        h = dt / n
        bank = s.bank_deg
        out = s
        for _ in range(n):
            change = (asked - bank) * (1.0 - math.exp(-h / self.tau))
            bank += min(max(change, -self.rate * h), self.rate * h)
            # The arc at the bank reached: a = -g tan(bank) (a left turn is a left bank).
            a = -G * math.tan(math.radians(bank))
            out = step(out, env, a, climb_rate, h, wind, eas2tas)
        return out


class RollLagFlightModel:
    """The point mass with the roll lag as a dry run's flight model (no limits of its own)."""

    name = "point mass, roll lag"

    def describe(self) -> str:
        return (
            f"point mass with a roll lag (first order {ROLL_TAU_S:g} s, at most "
            f"{ROLL_RATE_DEG_S:g} deg/s)"
        )

    def airframe(
        self,
        start: AircraftState,
        airspeed: float,
        alt_offset: float,
        wind: tuple[float, float] = (0.0, 0.0),
    ) -> RollLagPointMass:
        return RollLagPointMass()

    def limits(self, needs: object, eas: float) -> list[str]:
        return []
