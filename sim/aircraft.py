"""The aircraft: a point-mass fixed wing flying through a moving air mass.

It holds an equivalent airspeed (EAS, what both autopilots hold: ArduPlane AIRSPEED_CRUISE, PX4
FW_AIRSPD_TRIM) and so flies through the air at the true airspeed TAS = EAS * EAS2TAS(altitude)
(sim/atmosphere.py, ISA). Its heading is where its nose points in the air; its course is where
it goes over the ground: the air velocity plus the wind (sim/wind.py). The autopilot asks for a
lateral acceleration (L1 and npfg both compute one from the ground velocity) and a climb rate;
the aircraft asks for the bank atan(a / g), clipped to the autopilot's roll limit (ArduPlane
ROLL_LIMIT_DEG, PX4 FW_R_LIM), and rolls towards it as a first-order lag of ROLL_TAU_S, at most
ROLL_RATE_DEG_S (the bank is part of the state, carried from step to step); the bank reached
turns its heading at g tan(bank) / TAS. The climb rate is clipped to the autopilot's climb and
sink rates (ArduPlane TECS_CLMB_MAX / TECS_SINK_MAX, PX4 in missions FW_T_CLMB_R_SP /
FW_T_SINK_R_SP) and to its pitch limit (TAS sin(TECS_PITCH_MAX / FW_P_LIM_MAX): ``Envelope``)
and flown at once: no pitch dynamics. Rising or sinking air (sim/turbulence.py) carries the
aircraft up or down with it.

A step is flown in substeps of at most ROLL_SUBSTEP_S while the bank moves, each integrating the
air-relative motion exactly on the arc of constant heading rate at the bank reached there, and
adds the wind's drift over the step; once the bank is within ROLL_SETTLED_DEG of the one asked
the rest of the step is one arc, and within ROLL_ONE_ARC_DEG_S / dt the whole step is one arc at
the lag's mean turn rate. So a coarse fixed step (0.5 s at 25 m/s: 12.5 m) flies a
circle in still air as a circle, and its trochoid in a steady wind as the trochoid.
``arc_step`` is the step at a bank taken at once (the model before the roll lag, kept for the
cross-check and as the substep); sim/flight_kernel.py ``_step`` is the compiled twin of ``step``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from gcs_planner.aircraft.profile import ROLL_RESPONSE_S, G

# With unlimited climb (the contest's model) the aircraft still cannot fly straight up: it keeps
# this much of its airspeed horizontal.
STEEPEST_DEG = 89.0

# The roll-in (issue 31). Both autopilots' roll loops ask for a roll rate of the bank error over
# a time constant: ArduPlane RLL2SRV_TCONST, 0.5 s by default (libraries/APM_Control/
# AP_RollController.cpp, "time constant in seconds from demanded to achieved roll angle"), PX4
# FW_R_TC, 0.4 s (src/modules/fw_att_control/fw_att_control_params.c), that rate limited by PX4
# FW_R_RMAX, 70 deg/s by default (same file; ArduPlane's RLL2SRV_RMAX is off by default). That
# is what the autopilot asks; the airframe's roll rate then lags the rate asked. The JSBSim
# c172r under the same loops (sim/jsbsim_airframe.py) reaches 42 of 45 degrees of bank in about
# 2 s: a first-order lag of 0.8 s (1 - exp(-2 / 0.8) = 92 %), which 0.4-0.5 s would reach in
# under 1.3 s. So the bank follows the one asked as a first-order lag of ROLL_TAU_S = 0.8 s,
# at most ROLL_RATE_DEG_S = 70 deg/s: the autopilots' time constant plus the airframe's lag,
# measured, and PX4's rate limit. (The planner's derived reserve counts the same lag: it is the
# aircraft's, gcs_planner.aircraft.profile.ROLL_RESPONSE_S.)
ROLL_TAU_S = ROLL_RESPONSE_S
ROLL_RATE_DEG_S = 70.0
# The bank's substep while it moves (a 0.5 s step is ten), and how close to the bank asked it
# counts as there (the rest of the step is one arc: a settled leg or circle costs one arc a
# step; 0.001 deg of bank turns a 25 m/s aircraft by 0.0004 deg/s).
ROLL_SUBSTEP_S = 0.05
ROLL_SETTLED_DEG = 1e-3
# Within ROLL_ONE_ARC_DEG_S / dt of the bank asked (L1's corrections on a leg, a circle held: a
# degree on a 0.5 s step, an eighth on a coarse 4 s one) the step is one arc at the bank whose
# turn rate is the lag's mean over the step, ending at the bank the lag reaches: the heading is
# the substeps' (tan is straight to 1e-4 over a degree) and the position within 3 cm (its error
# grows as the gap times dt^2); the substeps cost ten arcs a 0.5 s step. (Not where the rate
# limit binds: a gap over ROLL_RATE_DEG_S * ROLL_TAU_S, on a short step cut at a finish line.)
ROLL_ONE_ARC_DEG_S = 0.5


@dataclass(frozen=True)
class Envelope:
    """What the flight model enforces: the autopilot's limits at the current airspeed."""

    airspeed: float  # m/s, equivalent (EAS)
    bank_limit_deg: float  # >= 90: turns on the spot (straight-leg plans, R = 0)
    climb_rate: float  # m/s, > 0
    sink_rate: float  # m/s, > 0
    # The pitch limit of auto flight (ArduPlane TECS_PITCH_MAX, PX4 FW_P_LIM_MAX): TECS asks
    # for a pitch of the climb rate over the TAS and clips it there, so the aircraft climbs
    # at most TAS sin(limit) (the point mass has no angle of attack: the pitch is its flight
    # path). >= 90: none.
    pitch_limit_deg: float = 90.0
    # The autopilot's ground-speed floor (m/s; 0: none) and its largest airspeed (m/s EAS):
    # ArduPlane MIN_GNDSPD_CM, PX4 FW_GND_SPD_MIN (gcs_planner/aircraft/autopilot.py
    # ``ground_speed_floor``), AIRSPEED_MAX / FW_AIRSPD_MAX.
    ground_speed_floor: float = 0.0
    airspeed_max: float = math.inf

    def held_tas(self, tas: float, heading: float, wx: float, wy: float, eas2tas: float) -> float:
        """The TAS flown at ``heading`` (rad) in the wind (wx, wy): ``tas``, raised by the
        shortfall of the ground speed along the heading below the floor, up to the largest
        airspeed (PX4 FixedwingPositionControl.cpp get_auto_airspeed_setpoint, "groundspeed
        undershoot": the body-forward ground speed; ArduPlane navigation.cpp
        calc_gndspeed_undershoot, added to the airspeed demand in Attitude.cpp
        calc_airspeed_errors). At once: the autopilot's airspeed loop is not modelled."""
        if self.ground_speed_floor <= 0.0:
            return tas
        short = self.ground_speed_floor - (tas + wx * math.cos(heading) + wy * math.sin(heading))
        if short <= 0.0:
            return tas
        return max(tas, min(tas + short, self.airspeed_max * eas2tas))

    def climb_through_air(self, climb_rate: float, tas: float) -> float:
        """``climb_rate`` (m/s) within the autopilot's climb and sink rates and its pitch
        limit at ``tas``."""
        vz = min(max(climb_rate, -self.sink_rate), self.climb_rate)
        if self.pitch_limit_deg < 90.0:
            vz = min(vz, tas * math.sin(math.radians(self.pitch_limit_deg)))
        return vz

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


def arc_step(
    s: AircraftState,
    env: Envelope,
    lateral_accel: float,
    climb_rate: float,
    dt: float,
    wind: Sequence[float] = (0.0, 0.0),
    eas2tas: float = 1.0,
    heading: float | None = None,
) -> AircraftState:
    """Fly ``dt`` seconds at the bank of ``lateral_accel`` taken at once (m/s^2, positive to the
    left: a counter-clockwise turn) and ``climb_rate`` (m/s), both clipped to the envelope,
    through air moving at ``wind`` (east, north m/s, and up when given: the aircraft rises and
    sinks with the air, its climb rate over the sea the sum) at EAS2TAS ``eas2tas``: one exact
    arc. An aircraft without a turn limit (``env.free_turn``) takes ``heading`` as given
    instead."""
    psi0 = s.heading if s.heading is not None else s.course
    v = env.held_tas(env.airspeed * eas2tas, psi0, wind[0], wind[1], eas2tas)
    vz = env.climb_through_air(climb_rate, v)
    vh = math.sqrt(max(v * v - vz * vz, 0.0))
    if env.free_turn:
        a = 0.0
        psi0 = psi0 if heading is None else heading
        w = 0.0
    else:
        limit = env.max_lateral_accel
        a = min(max(lateral_accel, -limit), limit)
        w = a / v  # g tan(bank) / TAS with tan(bank) = a / g
    wx, wy = wind[0], wind[1]
    wz = wind[2] if len(wind) > 2 else 0.0
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
        s.z + vz * dt + wz * dt,
        math.atan2(gy, gx),
        s.t + dt,
        bank,
        vz + wz,
        _wrap(psi1),
        v,
        math.hypot(gx, gy),
    )


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def step(
    s: AircraftState,
    env: Envelope,
    lateral_accel: float,
    climb_rate: float,
    dt: float,
    wind: Sequence[float] = (0.0, 0.0),
    eas2tas: float = 1.0,
    heading: float | None = None,
) -> AircraftState:
    """Fly ``dt`` seconds asking for ``lateral_accel`` (m/s^2, positive to the left: a
    counter-clockwise turn) and ``climb_rate`` (m/s), both clipped to the envelope, through air
    moving at ``wind`` (east, north m/s, and up when given) at EAS2TAS ``eas2tas``, the bank
    rolling from the state's towards the one asked (module docstring). The bank is in the
    state, so a step can be flown again from any state it returned, shorter (cut at a finish
    line) or longer. An aircraft without a turn limit (``env.free_turn``) turns on the spot to
    ``heading``."""
    if env.free_turn:
        return arc_step(s, env, lateral_accel, climb_rate, dt, wind, eas2tas, heading)
    limit = env.bank_limit_deg
    asked = min(max(-math.degrees(math.atan(lateral_accel / G)), -limit), limit)
    n = max(1, math.ceil(dt / ROLL_SUBSTEP_S - 1e-9))
    h = dt / n
    keep = 1.0 - math.exp(-h / ROLL_TAU_S)
    most = ROLL_RATE_DEG_S * h
    bank = s.bank_deg
    gap = bank - asked
    if (
        ROLL_SETTLED_DEG < abs(gap) <= ROLL_RATE_DEG_S * ROLL_TAU_S
        and abs(gap) * dt <= ROLL_ONE_ARC_DEG_S
    ):
        # The lag's bank asked + gap e^(-t / tau): its mean over the step, its end.
        decay = math.exp(-dt / ROLL_TAU_S)
        mean = asked + gap * ROLL_TAU_S * (1.0 - decay) / dt
        out = arc_step(s, env, -G * math.tan(math.radians(mean)), climb_rate, dt, wind, eas2tas)
        out.bank_deg = asked + gap * decay
        return out
    out = s
    for i in range(n):
        if abs(asked - bank) <= ROLL_SETTLED_DEG:
            # There: the rest of the step is one arc at the bank asked.
            return arc_step(out, env, lateral_accel, climb_rate, dt - i * h, wind, eas2tas)
        bank += min(max((asked - bank) * keep, -most), most)
        # The arc at the bank reached: a = -g tan(bank) (a left turn is a left bank).
        out = arc_step(out, env, -G * math.tan(math.radians(bank)), climb_rate, h, wind, eas2tas)
    return out


class FlightModelFace(Protocol):
    """What the dry run asks of a flight model other than its point mass (sim/guidance.py
    ``fly``): ``InstantBankFlightModel`` here, sim/jsbsim_airframe.py ``FlightModel`` and
    ``CheckedPointMass``."""

    def describe(self) -> str:
        """The model in the report's words."""
        ...

    def limits(self, needs: Sequence[object], eas: float) -> list[str]:
        """Where and why the airframe cannot fly the legs (``guidance.leg_needs``) at ``eas``."""
        ...

    def airframe(
        self,
        start: AircraftState,
        airspeed: float,
        alt_offset: float,
        wind: tuple[float, float] = (0.0, 0.0),
    ) -> object | None:
        """What flies the navigator's demands from ``start`` (None: the point mass, compiled);
        raises sim/jsbsim_airframe.py ``AirframeLimit`` when it cannot start."""
        ...


class InstantBankPointMass:
    """The point mass banking at once to the bank asked (``arc_step``): the model before the roll
    lag, an airframe for sim/navigators/base.py kept for the cross-check."""

    exact = True
    step = staticmethod(arc_step)


class InstantBankFlightModel:
    """The instant-bank point mass as a dry run's flight model (no limits of its own)."""

    def describe(self) -> str:
        return "point mass banking at once (no roll lag)"

    def airframe(
        self,
        start: AircraftState,
        airspeed: float,
        alt_offset: float,
        wind: tuple[float, float] = (0.0, 0.0),
    ) -> InstantBankPointMass:
        return InstantBankPointMass()

    def limits(self, needs: object, eas: float) -> list[str]:
        return []
