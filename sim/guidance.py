"""Mode AUTO: the mock vehicle flies its stored mission as ArduPlane or PX4 would, in the air.

Each autopilot is one navigator (sim/navigators/: ArduPlane from commands_logic.cpp,
mode_loiter.cpp and AP_L1_Control; PX4 from mission_block.cpp, navigator_main.cpp and npfg.cpp,
sharing one base), reading the autopilot's own parameters (sim/navigators/params.py: the roll
limit, the climb and sink rates TECS flies a mission at, the loiter radius and its scaling, the
acceptance and switch distances), flying the point-mass aircraft of sim/aircraft.py at its
equivalent airspeed through the ISA atmosphere (sim/atmosphere.py) and the wind and gusts of
sim/wind.py, steering its INS estimate when an INS is given (sim/ins.py).

Both: DO_CHANGE_SPEED (param2 > 0) changes the airspeed from the next leg on; RTL and LAND end
the flight (the route is over); unknown items are skipped. The altitude is TECS's: the climb
rate asked is the demand's own plus the height error over the autopilot's time constant
(TECS_TIME_CONST, FW_T_ALT_TC), within its rates and pitch limit, and the vertical turbulence of
sim/wind.py moves the aircraft off it. Not modelled: roll and pitch dynamics, TECS's energy
exchange (the aircraft climbs at the rate asked as soon as asked), terrain.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from gcs_planner.sim import atmosphere, flight_kernel
from gcs_planner.sim.aircraft import AircraftState, FlightModelFace
from gcs_planner.sim.ins import InsEstimate
from gcs_planner.sim.jsbsim_airframe import AirframeLimit, LegNeed
from gcs_planner.sim.navigators import NAVIGATORS
from gcs_planner.sim.navigators.base import Navigator
from gcs_planner.sim.navigators.commands import (
    DO_CHANGE_SPEED,
    LOITERS,
    NAV_LAND,
    NAV_LOITER_TIME,
    NAV_LOITER_TO_ALT,
    NAV_LOITER_TURNS,
    NAV_LOITER_UNLIM,
    NAV_RETURN_TO_LAUNCH,
    NAV_TAKEOFF,
    NAV_WAYPOINT,
    Event,
    NavCommand,
)
from gcs_planner.sim.navigators.params import AutopilotParams
from gcs_planner.sim.navigators.state import COARSE_STEPS, DEFAULT_STEP_S
from gcs_planner.sim.navigators.steering import L1_DAMPING, L1_PERIOD_S
from gcs_planner.sim.wind import WindField, WindModel

from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT
from gcs_planner.aircraft.profile import G, VehicleProfile
from gcs_planner.mission.items import GLOBAL_AMSL_FRAMES, GLOBAL_RELATIVE_FRAMES, MissionItem
from gcs_planner.scenario.georef import LocalFrame

__all__ = [
    "COARSE_STEPS", "DEFAULT_STEP_S", "DO_CHANGE_SPEED", "L1_DAMPING", "L1_PERIOD_S", "LOITERS",
    "NAV_LAND", "NAV_LOITER_TIME", "NAV_LOITER_TO_ALT", "NAV_LOITER_TURNS", "NAV_LOITER_UNLIM",
    "NAV_RETURN_TO_LAUNCH", "NAV_TAKEOFF", "NAV_WAYPOINT", "ENDURANCE_ENDED", "AutopilotParams",
    "NOT_FLOWN", "Event", "Flight", "NavCommand", "WindModel", "fly", "nav_commands",
    "turn_radius_flown",
]  # fmt: skip


# Why a flight ended when its endurance ran out (``fly``'s ``endurance``).
ENDURANCE_ENDED = "endurance"
# How the flight of a mission the airframe cannot fly ends: it never started (``_unflown``).
NOT_FLOWN = "cannot be flown"


@dataclass(frozen=True)
class Flight:
    """The flown track (local frame, one sample per step, A first) and what happened."""

    t: np.ndarray
    xyz: np.ndarray  # (m, 3), the true position
    course: np.ndarray  # rad, counter-clockwise from east: over the ground
    bank: np.ndarray  # deg, right wing down positive
    climb: np.ndarray  # m/s
    airspeed: np.ndarray  # m/s, equivalent (what the autopilot holds)
    current: np.ndarray  # seq of the active item at each sample
    events: tuple[Event, ...]
    # why the flight ended: "mission end", "loiter at end", "landing", "time limit", "lost",
    # ENDURANCE_ENDED
    ended: str
    notes: tuple[str, ...] = field(default=())
    heading: np.ndarray | None = None  # rad: through the air (differs from course in wind)
    tas: np.ndarray | None = None  # m/s, true airspeed
    ground_speed: np.ndarray | None = None  # m/s
    autopilot: AutopilotParams | None = None
    wind: WindModel | None = None
    # Flown by another flight model (sim/jsbsim_airframe.py): its name, what it found it
    # cannot fly before the flight (where and why), and what it could not hold in flight.
    flight_model: str = "point mass"
    limits: tuple[str, ...] = field(default=())
    shortfalls: tuple[str, ...] = field(default=())

    @cached_property
    def cumulative(self) -> np.ndarray:
        seg = np.linalg.norm(np.diff(self.xyz, axis=0), axis=1)
        return np.concatenate([[0.0], np.cumsum(seg)])

    @property
    def duration(self) -> float:
        return float(self.t[-1]) if len(self.t) else 0.0


def nav_commands(
    items: Sequence[MissionItem],
    frame: LocalFrame,
    base_alt: float,
    *,
    home_at_seq0: bool,
) -> list[NavCommand]:
    """The stored items as commands in the local frame; altitudes of relative frames are above
    ``base_alt`` (home). Item 0 is home on ArduPilot and not flown."""
    out = []
    for it in items:
        if home_at_seq0 and it.seq == 0:
            continue
        pos = None
        if it.frame in GLOBAL_AMSL_FRAMES or it.frame in GLOBAL_RELATIVE_FRAMES:
            alt = it.z + (base_alt if it.frame in GLOBAL_RELATIVE_FRAMES else 0.0)
            x, y, z = frame.to_local(it.x / 1e7, it.y / 1e7, alt)
            pos = (float(x), float(y), float(z))
        params = (it.param1, it.param2, it.param3, it.param4)
        out.append(NavCommand(it.seq, it.command, pos, params))
    return out


def mission_commands(
    items: Sequence[MissionItem],
    frame: LocalFrame,
    start: tuple[float, float, float],
    *,
    home_at_seq0: bool = False,
    home_alt: float | None = None,
) -> list[NavCommand]:
    """The commands ``fly`` flies for ``items`` from ``start`` (its ``commands``)."""
    base_alt = float(start[2] + frame.origin.alt) if home_alt is None else home_alt
    return nav_commands(items, frame, base_alt, home_at_seq0=home_at_seq0)


def initial_course(cmds: Sequence[NavCommand], start: tuple[float, float, float]) -> float:
    """The heading at the start when none is given: towards the first item that is not a
    loiter. A loiter's position is its centre, off the path: aiming at the first other item puts
    an aircraft that starts a helix at A on its circle's tangent (the planner's free heading at
    A)."""
    positions = [c.pos for c in cmds if c.pos is not None]
    aims = [c.pos for c in cmds if c.pos is not None and c.command not in LOITERS]
    for p in aims or positions:
        if math.hypot(p[0] - start[0], p[1] - start[1]) > 1.0:
            return math.atan2(p[1] - start[1], p[0] - start[0])
    return 0.0


def default_time_limit(
    cmds: Sequence[NavCommand],
    start: tuple[float, float, float],
    profile: VehicleProfile,
    wind: WindModel | None,
) -> float:
    """Three times the time to fly the items' chords plus ten minutes: stops an aircraft that
    never finishes."""
    pts = [start, *(c.pos for c in cmds if c.pos is not None)]
    chords = sum(math.dist(p, q) for p, q in zip(pts, pts[1:], strict=False))
    slowest = max(profile.cruise_airspeed - (wind.speed + 3 * wind.gust if wind else 0), 5.0)
    return 3.0 * chords / slowest + 600.0


def fly(
    items: Sequence[MissionItem],
    frame: LocalFrame,
    start: tuple[float, float, float],
    profile: VehicleProfile,
    *,
    flavour: str = DEFAULT_AUTOPILOT,
    params: AutopilotParams | None = None,
    home_at_seq0: bool = False,
    home_alt: float | None = None,
    course: float | None = None,
    dt: float = DEFAULT_STEP_S,
    time_limit: float | None = None,
    wind: WindModel | None = None,
    ins: InsEstimate | None = None,
    compiled: bool = True,
    commands: Sequence[NavCommand] | None = None,
    flight_model: FlightModelFace | None = None,
    endurance: float | None = None,
) -> Flight:
    """Fly the stored ``items`` in mode AUTO from ``start`` (local frame) at ``profile``'s cruise
    airspeed (EAS) under ``flavour``'s navigator with the autopilot ``params`` (by default its
    shipped limits, the loiter radius the profile's turning radius), in fast-forward time with a
    fixed step ``dt``, through ``wind`` (default still air), steering the estimate of ``ins``
    (sim/ins.py) when given. A profile with turning radius 0 (straight-leg plans, the contest's
    model) turns on the spot: the one idealisation kept, and said by the dry run.

    ``course`` is the heading at the start (rad, counter-clockwise from east), by default
    towards the first item that is not a loiter. ``time_limit`` (s) stops an aircraft that never
    finishes, by default three times the time to fly the items' chords plus ten minutes.

    ``compiled`` flies the plain steps and waypoints (sim/flight_kernel.py) in the numba
    kernel; False flies every step in the Python navigator, the reference. ``commands``: the
    items as mission_commands gives them for these arguments, when the caller has them (a
    Monte Carlo flies one mission many times).

    ``flight_model`` (sim/jsbsim_airframe.py ``FlightModel``) flies the navigator's demands in
    JSBSim instead of the point mass (sim/aircraft.py ``step``, rolling into its turns), all in
    Python; sim/aircraft.py ``InstantBankFlightModel`` flies the point mass banking at once (the
    model before issue 31, for the cross-check), in Python too; sim/jsbsim_airframe.py
    ``CheckedPointMass`` checks the legs against a JSBSim aircraft and leaves the flight to the
    point mass (compiled as without a model). The legs are checked against the airframe first
    (``Flight.limits``): a mission with any leg the airframe cannot fly, or an airframe that
    cannot be trimmed at the start, is not flown (``ended`` "cannot be flown").

    ``endurance`` (s): the flight the aircraft's battery or fuel gives from the start; past it
    the low-battery failsafe (ArduPlane BATT_FS_LOW_ACT, PX4 COM_LOW_BAT_ACT) ends the mission
    where the aircraft is (``ended`` ENDURANCE_ENDED).
    """
    ap = params or AutopilotParams(flavour=flavour, loiter_radius=profile.turn_radius)
    if commands is None:
        commands = mission_commands(
            items, frame, start, home_at_seq0=home_at_seq0, home_alt=home_alt
        )
    cmds = list(commands)
    if course is None:
        course = initial_course(cmds, start)
    if time_limit is None:
        time_limit = default_time_limit(cmds, start, profile, wind)
    s0 = AircraftState(float(start[0]), float(start[1]), float(start[2]), course)
    field_ = None if wind is None or wind.still else WindField(wind, profile.cruise_airspeed)
    airframe = None
    limits: list[str] = []
    if flight_model is not None:
        alt = float(frame.origin.alt)
        limits = flight_model.limits(
            leg_needs(cmds, start, alt, profile, ap), profile.cruise_airspeed
        )
        try:
            airframe = flight_model.airframe(
                s0, profile.cruise_airspeed, alt, field_.current() if field_ else (0.0, 0.0)
            )
        except AirframeLimit as exc:
            limits.insert(0, str(exc))
        if limits:
            # No trim at the start, or a leg above the airframe's ceiling, beyond its climb or
            # its bank: refused before the flight starts (issue 52), nothing flown.
            return _unflown(s0, profile, ap, wind, flight_model, limits)
    if airframe is not None:  # None: the dry run's point mass flies (a model that only checks)
        compiled = False  # the numba kernel flies the point mass only
        # A model that cannot cut a step at a waypoint's acceptance circle or finish line
        # (JSBSim) is stepped finer: the switch comes at most one such step late.
        dt = min(dt, getattr(flight_model, "outer_step", dt))
    pilot = NAVIGATORS[ap.flavour](
        cmds,
        profile.cruise_airspeed,
        ap,
        s0,
        dt,
        free_turn=profile.turn_radius <= 0,
        wind=field_,
        alt_offset=float(frame.origin.alt),
        ins=ins,
        airframe=airframe,
    )
    _fly_mission(pilot, ins, compiled, time_limit, endurance)
    arr = np.asarray(pilot.samples, float)
    return Flight(
        t=arr[:, 0],
        xyz=arr[:, 1:4],
        course=arr[:, 4],
        bank=arr[:, 5],
        climb=arr[:, 6],
        airspeed=arr[:, 7],
        current=arr[:, 8].astype(int),
        events=tuple(pilot.events),
        ended=pilot.ended,
        notes=tuple(pilot.notes),
        heading=arr[:, 9],
        tas=arr[:, 10],
        ground_speed=arr[:, 11],
        autopilot=ap,
        wind=wind,
        flight_model="point mass" if flight_model is None else flight_model.describe(),
        limits=tuple(limits),
        shortfalls=_shortfalls(airframe, arr),
    )


def _fly_mission(
    pilot: Navigator,
    ins: InsEstimate | None,
    compiled: bool,
    time_limit: float,
    endurance: float | None,
) -> None:
    """Fly ``pilot``'s mission from its first item until it ends, is lost on arrival at a
    landmark, runs out of ``endurance`` (s) or reaches ``time_limit`` (s); the plain steps in
    the compiled flight when ``compiled``."""
    pilot.record()
    going = pilot.advance()
    cache: dict = {}
    stop_at = time_limit if endurance is None else min(time_limit, endurance)
    while going:
        if compiled:
            flight_kernel.fly_plain_steps(pilot, stop_at, cache)
        if ins is not None and getattr(ins, "lost", False):
            # Lost on arrival at a correction landmark: nothing after it counts.
            pilot.ended = "lost"
            break
        if endurance is not None and pilot.s.t >= endurance:
            pilot.ended = ENDURANCE_ENDED
            pilot.event(pilot.cmds[pilot.k].seq, "end",
                        f"out of endurance after {endurance / 60:g} min: the low-battery "
                        "failsafe ends the mission")  # fmt: skip
            break
        if pilot.s.t >= time_limit:
            pilot.ended = "time limit"
            pilot.event(pilot.cmds[pilot.k].seq, "end", f"still flying after {time_limit:.0f} s")
            break
        going = pilot.tick()


def _shortfalls(airframe: object, samples: np.ndarray) -> tuple[str, ...]:
    """The airframe's in-flight shortfalls, each with the item being flown and where."""
    out = []
    for sf in getattr(airframe, "shortfalls", ()):
        k = min(int(np.searchsorted(samples[:, 0], sf.t)), len(samples) - 1)
        out.append(
            f"{sf.kind} on the way to item {int(samples[k, 8])} at ({sf.x:,.0f}, {sf.y:,.0f}) m, "
            f"{sf.t:.0f} s: {sf.text}"
        )
    return tuple(out)


def _unflown(
    s0: AircraftState,
    profile: VehicleProfile,
    ap: AutopilotParams,
    wind: WindModel | None,
    model: FlightModelFace,
    limits: list[str],
) -> Flight:
    """The flight of an airframe that could not start: one sample where it stands."""
    one = np.array([0.0])
    return Flight(
        t=one, xyz=np.array([[s0.x, s0.y, s0.z]]), course=np.array([s0.course]),
        bank=np.zeros(1), climb=np.zeros(1), airspeed=np.array([profile.cruise_airspeed]),
        current=np.array([-1]), events=(), ended=NOT_FLOWN, notes=(),
        heading=np.array([s0.course]), tas=np.zeros(1), ground_speed=np.zeros(1),
        autopilot=ap, wind=wind, flight_model=model.describe(), limits=tuple(limits),
    )  # fmt: skip


def leg_needs(
    cmds: Sequence[NavCommand],
    start: tuple[float, float, float],
    alt_offset: float,
    profile: VehicleProfile,
    ap: AutopilotParams,
) -> list[LegNeed]:
    """What each leg asks of the airframe: its top altitude (above sea level), its flight-path
    angle (a straight leg's slope; a loiter's helix at the plan's climb angle, or the
    autopilot's climb rate when that is less), the bank its turns need at the top: the plan's
    turning radius (a loiter's own radius) at the true airspeed there, within the roll limit."""
    out = []
    prev = start
    roll_limit = float(ap.bank_limit or 45.0)
    for c in cmds:
        if c.pos is None:
            continue
        top = max(prev[2], c.pos[2]) + alt_offset
        tas = profile.cruise_airspeed * atmosphere.eas2tas(top)
        dz = c.pos[2] - prev[2]
        run = math.hypot(c.pos[0] - prev[0], c.pos[1] - prev[1])
        radius = profile.turn_radius
        if c.command in LOITERS:
            signed = c.params[1] if c.command == NAV_LOITER_TO_ALT else c.params[2]
            radius = abs(signed) or radius
            rate = float(ap.climb_rate or 5.0) if dz > 0 else float(ap.sink_rate or 5.0)
            steepest = math.degrees(math.asin(min(rate / tas, 1.0)))
            plan = profile.max_climb_angle if dz > 0 else profile.max_descent_angle
            gamma = math.copysign(min(steepest, plan), dz) if abs(dz) > 1.0 else 0.0
        else:
            gamma = math.degrees(math.atan2(dz, run)) if run > 1.0 else 0.0
        bank = math.degrees(math.atan(tas * tas / (G * radius))) if radius > 0 else 0.0
        out.append(LegNeed(c.seq, top, gamma, min(bank, roll_limit)))
        prev = c.pos
    return out


def turn_radius_flown(bank_deg: float, airspeed: float) -> float:
    """Radius of a coordinated turn at ``bank_deg`` (inf when wings level)."""
    t = math.tan(math.radians(abs(bank_deg)))
    return math.inf if t < 1e-12 else airspeed * airspeed / (G * t)
