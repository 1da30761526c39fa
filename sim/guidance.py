"""Mode AUTO: the mock vehicle flies its stored mission as ArduPlane or PX4 would, in the air.

Each autopilot is one navigator (sim/navigators/: ArduPlane from commands_logic.cpp,
mode_loiter.cpp and AP_L1_Control; PX4 from mission_block.cpp, navigator_main.cpp and npfg.cpp,
sharing one base), reading the autopilot's own parameters (sim/navigators/params.py: the roll
limit, the climb and sink rates TECS flies a mission at, the loiter radius and its scaling, the
acceptance and switch distances), flying the point-mass aircraft of sim/aircraft.py at its
equivalent airspeed through the ISA atmosphere (sim/atmosphere.py) and the wind and gusts of
sim/wind.py, steering its INS estimate when an INS is given (sim/ins.py).

Both: DO_CHANGE_SPEED (param2 > 0) changes the airspeed from the next leg on; RTL and LAND end
the flight (the route is over); unknown items are skipped. Not modelled: roll and pitch
dynamics, TECS energy exchange (the aircraft climbs at its rate as soon as asked), vertical
gusts, terrain.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from gcs_planner.mission.items import GLOBAL_AMSL_FRAMES, GLOBAL_RELATIVE_FRAMES, MissionItem
from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.vehicle import G, VehicleProfile
from sim import flight_kernel
from sim.aircraft import AircraftState
from sim.navigators import NAVIGATORS
from sim.navigators.base import (
    COARSE_STEPS,
    DEFAULT_STEP_S,
    DO_CHANGE_SPEED,
    L1_DAMPING,
    L1_PERIOD_S,
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
from sim.navigators.params import AutopilotParams
from sim.wind import WindField, WindModel

__all__ = [
    "COARSE_STEPS", "DEFAULT_STEP_S", "DO_CHANGE_SPEED", "L1_DAMPING", "L1_PERIOD_S", "LOITERS",
    "NAV_LAND", "NAV_LOITER_TIME", "NAV_LOITER_TO_ALT", "NAV_LOITER_TURNS", "NAV_LOITER_UNLIM",
    "NAV_RETURN_TO_LAUNCH", "NAV_TAKEOFF", "NAV_WAYPOINT", "AutopilotParams", "Event", "Flight",
    "NavCommand", "WindModel", "fly", "nav_commands", "turn_radius_flown",
]  # fmt: skip


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
    ended: str  # why the flight ended: "mission end", "loiter at end", "landing", "time limit"
    notes: tuple[str, ...] = field(default=())
    heading: np.ndarray | None = None  # rad: through the air (differs from course in wind)
    tas: np.ndarray | None = None  # m/s, true airspeed
    ground_speed: np.ndarray | None = None  # m/s
    autopilot: AutopilotParams | None = None
    wind: WindModel | None = None

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
    flavour: str = "ardupilot",
    params: AutopilotParams | None = None,
    home_at_seq0: bool = False,
    home_alt: float | None = None,
    course: float | None = None,
    dt: float = DEFAULT_STEP_S,
    time_limit: float | None = None,
    wind: WindModel | None = None,
    ins: object | None = None,
    compiled: bool = True,
    commands: Sequence[NavCommand] | None = None,
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
    )
    pilot.record()
    going = pilot.advance()
    cache: dict = {}
    while going:
        if compiled:
            flight_kernel.fly_plain_steps(pilot, time_limit, cache)
        if ins is not None and getattr(ins, "lost", False):
            # Lost on arrival at a correction landmark: nothing after it counts.
            pilot.ended = "lost"
            break
        if pilot.s.t >= time_limit:
            pilot.ended = "time limit"
            pilot.event(pilot.cmds[pilot.k].seq, "end", f"still flying after {time_limit:.0f} s")
            break
        going = pilot.tick()
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
    )


def turn_radius_flown(bank_deg: float, airspeed: float) -> float:
    """Radius of a coordinated turn at ``bank_deg`` (inf when wings level)."""
    t = math.tan(math.radians(abs(bank_deg)))
    return math.inf if t < 1e-12 else airspeed * airspeed / (G * t)
