"""Mode AUTO: the mock vehicle flies its stored mission as ArduPlane or PX4 would.

Modelled (not copied) from the autopilots' own sources, read for this module:

ArduPlane (ArduPlane/commands_logic.cpp, ArduPlane/navigation.cpp, libraries/AP_L1_Control):

* Lateral guidance is L1 (Park, Deyst, How 2004) on the line from the previous waypoint to the
  active one: lateral acceleration K V^2 / L1 sin(Nu), K = 4 damping^2, L1 = damping period V / pi
  (NAVL1_PERIOD 17 s, NAVL1_DAMPING 0.75), Nu the sum of the intercept angle asin(xtrack / L1),
  limited to 45 degrees, and the track-angle error. Behind the previous waypoint and farther than
  L1 from it, the aircraft heads for it first.
* NAV_WAYPOINT is reached (verify_nav_wp) within its acceptance radius, param2 (a whole number
  of metres, 0..255) or, when param2 is 0, the L1 turn distance min(WP_RADIUS, L1) scaled by the
  turn to the next leg / 90 degrees; or once past the finish line, the perpendicular to the track
  through the waypoint. Altitude is not checked: the target altitude slides from the previous
  waypoint's to this one's in proportion to the horizontal distance flown (the glide slope), and
  a waypoint whose altitude the aircraft could not reach is passed all the same; the aircraft
  keeps climbing or sinking at its limit towards the next target.
* The next leg starts at the reached waypoint, or at the aircraft when it is already past the
  new leg's finish line (set_next_WP).
* Loiters circle the item's position on |param3| (LOITER_TO_ALT: |param2|; 0: WP_LOITER_RAD),
  clockwise when positive. LOITER_TURNS counts param1 turns once on the circle; LOITER_TO_ALT
  circles until the altitude is within 5 m; LOITER_TIME for param1 seconds. Each then waits
  until the course points at the next waypoint within 10 degrees, plus 10 per lap flown
  (verify_loiter_heading, mode_loiter.cpp isHeadingLinedUp_cd), and leaves towards it; with
  param4 (xtrack) > 0 the next leg is tracked from the exit point, otherwise from the loiter's
  centre. LOITER_UNLIM circles for ever: the flight ends there.

PX4 (src/modules/navigator/mission_block.cpp, src/modules/fw_pos_control/
FixedwingPositionControl.cpp):

* Lateral guidance is modelled with the same L1 law (PX4's npfg tracks the line with the same
  structure; its own gains are not modelled).
* NAV_WAYPOINT is reached (is_mission_item_reached) within NAV_ACC_RAD horizontally, param2 is
  used by multicopters only, or once past the waypoint along the previous-to-current line; AND
  within NAV_FW_ALT_RAD (10 m) of its altitude. An aircraft that comes to the waypoint too high or
  too low circles it on NAV_LOITER_RAD until the altitude is in (handle_setpoint_type: position
  setpoint turned into a loiter), then leaves with its course on the next waypoint (12 degrees,
  MIS_YAW_ERR). The altitude target slides linearly to the waypoint's, reached at the acceptance
  radius (the "altitude first-order hold").
* LOITER_TO_ALT (mavlink_mission.cpp: param1 heading required, param2 the signed radius, param4
  cross-track exit) keeps the current altitude until on the circle, then climbs or sinks to the
  item's; reached within NAV_FW_ALT_RAD, wherever on the circle (no turns counted). With the
  heading required, and the next waypoint farther than 1.2 radii from the centre, it then waits
  for the course to point at the next waypoint (MIS_YAW_ERR). With param4 > 0 the next leg starts
  at the tangent point PX4 computes from the centre towards the next waypoint, not where the
  aircraft is. LOITER_TIME: param2 heading required, param3 the radius.
* A leg whose previous and current setpoints coincide has no "passed" line on PX4 (it is checked
  only for a segment longer than 1e-6 m): such a waypoint is reached within NAV_ACC_RAD only.
* LOITER_TURNS is not a position item in PX4's navigator (item_contains_position): it is
  skipped, as are DO items other than DO_CHANGE_SPEED.

Both: DO_CHANGE_SPEED (param2 > 0) changes the airspeed from the next leg on; RTL and LAND end
the flight (the route is over); unknown items are skipped. Not modelled: wind, roll and pitch
dynamics, TECS energy exchange (the aircraft climbs at its limit as soon as asked), terrain.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from gcs_planner.mission.georef import LocalFrame
from gcs_planner.mission.items import MissionItem
from gcs_planner.vehicle import (
    DEFAULT_ACCEPTANCE_RADIUS_M,
    G,
    VehicleProfile,
)
from sim.aircraft import AircraftState, envelope_of, step

NAV_WAYPOINT = 16
NAV_LOITER_UNLIM = 17
NAV_LOITER_TURNS = 18
NAV_LOITER_TIME = 19
NAV_RETURN_TO_LAUNCH = 20
NAV_LAND = 21
NAV_TAKEOFF = 22
NAV_LOITER_TO_ALT = 31
DO_CHANGE_SPEED = 178
LOITERS = frozenset({NAV_LOITER_UNLIM, NAV_LOITER_TURNS, NAV_LOITER_TIME, NAV_LOITER_TO_ALT})
GLOBAL_AMSL_FRAMES = frozenset({0, 5})
GLOBAL_RELATIVE_FRAMES = frozenset({3, 6})

# ArduPlane defaults: NAVL1_PERIOD, NAVL1_DAMPING; the altitude a loiter-to-altitude accepts.
L1_PERIOD_S = 17.0
L1_DAMPING = 0.75
ARDUPLANE_LOITER_ALT_M = 5.0
ARDUPLANE_EXIT_HEADING_DEG = 10.0
# PX4 defaults: NAV_FW_ALT_RAD, MIS_YAW_ERR.
PX4_ALT_ACCEPTANCE_M = 10.0
PX4_EXIT_HEADING_DEG = 12.0
# TECS altitude time constant (ArduPlane TECS_TIME_CONST, PX4 FW_T_ALT_TC): 5 s.
ALTITUDE_TIME_CONSTANT_S = 5.0
# The step of the fast-forward flight (see sim/aircraft.py: arcs are integrated exactly). On a
# straight leg where the aircraft is settled on the track and its glide slope (cross-track under
# 0.5 m, course within 0.3 degrees, altitude within 0.5 m, far from the waypoint) nothing changes
# but the position, so the step grows COARSE_STEPS times: the long legs of a 170 km mission cost
# little, the turns keep the fine step.
DEFAULT_STEP_S = 0.5
COARSE_STEPS = 8


@dataclass(frozen=True)
class AutopilotParams:
    """The autopilot's own parameters the guidance reads (served by the mock vehicle)."""

    flavour: str = "ardupilot"
    wp_radius: float = 90.0  # ArduPlane WP_RADIUS
    loiter_radius: float = 200.0  # ArduPlane WP_LOITER_RAD / PX4 NAV_LOITER_RAD (signed: + CW)
    acceptance_radius: float = 10.0  # PX4 NAV_ACC_RAD

    @classmethod
    def from_parameters(cls, flavour: str, params: dict[str, float]) -> AutopilotParams:
        if flavour == "ardupilot":
            return cls(
                flavour,
                wp_radius=float(params.get("WP_RADIUS", 90.0)),
                loiter_radius=float(params.get("WP_LOITER_RAD", 200.0)),
                acceptance_radius=float(params.get("WP_RADIUS", DEFAULT_ACCEPTANCE_RADIUS_M)),
            )
        return cls(
            flavour,
            wp_radius=float(params.get("NAV_ACC_RAD", 10.0)),
            loiter_radius=float(params.get("NAV_LOITER_RAD", 200.0)),
            acceptance_radius=float(params.get("NAV_ACC_RAD", 10.0)),
        )


@dataclass(frozen=True)
class NavCommand:
    """One mission item the guidance acts on, its position in the local frame when it has one."""

    seq: int
    command: int
    pos: tuple[float, float, float] | None
    params: tuple[float, float, float, float]


@dataclass(frozen=True)
class Event:
    """Something the autopilot did: ``kind`` "reached", "skipped" or "end"; ``sample`` the
    index of the track sample at that moment."""

    t: float
    sample: int
    seq: int
    kind: str
    text: str = ""


@dataclass(frozen=True)
class Flight:
    """The flown track (local frame, one sample per step, A first) and what happened."""

    t: np.ndarray
    xyz: np.ndarray  # (m, 3)
    course: np.ndarray  # rad, counter-clockwise from east
    bank: np.ndarray  # deg, right wing down positive
    climb: np.ndarray  # m/s
    airspeed: np.ndarray  # m/s
    current: np.ndarray  # seq of the active item at each sample
    events: tuple[Event, ...]
    ended: str  # why the flight ended: "mission end", "loiter at end", "landing", "time limit"
    notes: tuple[str, ...] = field(default=())

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


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


class _Autopilot:
    """The state of mode AUTO over one flight."""

    def __init__(
        self,
        commands: list[NavCommand],
        profile: VehicleProfile,
        ap: AutopilotParams,
        start: AircraftState,
        dt: float,
    ) -> None:
        self.cmds = commands
        self.profile = profile
        self.ap = ap
        self.px4 = ap.flavour == "px4"
        self.dt = dt
        self.s = start
        self.env = envelope_of(profile)
        self.samples: list[tuple] = []
        self.events: list[Event] = []
        self.notes: list[str] = []
        self.k = -1  # index of the active command
        self.prev = (start.x, start.y, start.z)
        self.phase = "track"  # "track" | "loiter" | "exit"
        self.loiter_sum = 0.0
        self.loiter_started = False
        self.loiter_t0 = 0.0
        self.min_dist = math.inf
        self.hold_alt: float | None = None
        self.ended = ""
        self.settled = False  # on the track and the glide slope (see COARSE_STEPS)
        self.alt_error = 0.0

    # The mission sequence ------------------------------------------------------------------
    def _record(self) -> None:
        s = self.s
        seq = self.cmds[self.k].seq if 0 <= self.k < len(self.cmds) else -1
        self.samples.append(
            (s.t, s.x, s.y, s.z, s.course, s.bank_deg, s.climb_rate, self.env.airspeed, seq)
        )

    def _event(self, seq: int, kind: str, text: str = "") -> None:
        self.events.append(Event(self.s.t, len(self.samples) - 1, seq, kind, text))

    def _next_nav_index(self, start: int) -> int | None:
        for j in range(start, len(self.cmds)):
            c = self.cmds[j]
            if self._flies(c):
                return j
        return None

    def _flies(self, c: NavCommand) -> bool:
        if c.command in (NAV_RETURN_TO_LAUNCH,):
            return True
        if c.pos is None:
            return False
        if c.command == NAV_LOITER_TURNS and self.px4:
            return False
        return c.command in (NAV_WAYPOINT, NAV_TAKEOFF, NAV_LAND) or c.command in LOITERS

    def advance(self) -> bool:
        """Make the next command active; run the DO items on the way. False at the end."""
        j = self.k + 1
        while j < len(self.cmds):
            c = self.cmds[j]
            if self._flies(c):
                break
            if c.command == DO_CHANGE_SPEED and c.params[1] > 0:
                self.env = envelope_of(self.profile, c.params[1])
            elif c.command == NAV_LOITER_TURNS and self.px4:
                self.notes.append(f"item {c.seq}: PX4 does not fly LOITER_TURNS; skipped")
                self._event(c.seq, "skipped", "LOITER_TURNS is not a PX4 position item")
            elif c.command != DO_CHANGE_SPEED:
                self._event(c.seq, "skipped")
            j += 1
        self.k = j
        self.phase = "track"
        self.loiter_sum = 0.0
        self.loiter_started = False
        self.min_dist = math.inf
        self.hold_alt = None
        if j >= len(self.cmds):
            self.ended = "mission end"
            return False
        c = self.cmds[j]
        if c.command == NAV_RETURN_TO_LAUNCH:
            self.ended = "return to launch"
            return False
        assert c.pos is not None
        # set_next_WP: already past the new leg's finish line, track it from here.
        px, py = self.prev[0], self.prev[1]
        if (self.s.x - c.pos[0]) * (c.pos[0] - px) + (self.s.y - c.pos[1]) * (c.pos[1] - py) > 0:
            self.prev = (self.s.x, self.s.y, self.s.z)
        if c.command == NAV_LOITER_TO_ALT and self.px4:
            self.hold_alt = self.s.z
        return True

    def reached(self, c: NavCommand, how: str, exit_from: tuple | None = None) -> bool:
        assert c.pos is not None
        self._event(c.seq, "reached", how)
        self.prev = exit_from or c.pos
        return self.advance()

    # Geometry ------------------------------------------------------------------------------
    def _next_target(self) -> tuple[float, float, float] | None:
        j = self._next_nav_index(self.k + 1)
        return None if j is None else self.cmds[j].pos

    def _loiter_geometry(self, c: NavCommand) -> tuple[float, int]:
        """(radius, direction: +1 counter-clockwise, -1 clockwise) of a loiter item. The signed
        radius is param3 of the loiters, but param2 of LOITER_TO_ALT (common.xml; PX4's
        mavlink_mission.cpp and ArduPilot's AP_Mission read it there)."""
        p = c.params[1] if c.command == NAV_LOITER_TO_ALT else c.params[2]
        signed = p if abs(p) > 0 and c.command != NAV_WAYPOINT else self.ap.loiter_radius
        radius = abs(signed)
        radius = max(radius, self.env.min_radius)
        return radius, (-1 if signed >= 0 else 1)

    # Lateral guidance ----------------------------------------------------------------------
    def _ground_speed(self) -> float:
        """Horizontal speed of the last step: L1 works on the ground track, so a steep climb
        (slow over the ground) shortens L1 and slows the turns it asks for."""
        v, vz = self.env.airspeed, self.s.climb_rate
        return max(math.sqrt(max(v * v - vz * vz, 0.0)), 1e-3)

    def _l1_line(self, a: tuple, b: tuple) -> float:
        """Turn rate (rad/s) of L1 guidance on the line a -> b."""
        s, v = self.s, self._ground_speed()
        l1 = L1_DAMPING * L1_PERIOD_S * v / math.pi
        abx, aby = b[0] - a[0], b[1] - a[1]
        n = math.hypot(abx, aby)
        if n < 1e-6:
            abx, aby = b[0] - s.x, b[1] - s.y
            n = math.hypot(abx, aby) or 1.0
        ux, uy = abx / n, aby / n
        ax, ay = s.x - a[0], s.y - a[1]
        cx, cy = math.cos(s.course), math.sin(s.course)
        dist_a = math.hypot(ax, ay)
        along = ax * ux + ay * uy
        self.settled = False
        if dist_a > l1 and along < -0.7071 * dist_a:
            # Behind the start of the leg and far: head for it (AP_L1_Control).
            nu = _wrap(math.atan2(-ay, -ax) - s.course)
        else:
            xtrack = ux * ay - uy * ax  # > 0: left of the track
            nu1 = math.asin(max(-0.7071, min(0.7071, xtrack / l1)))
            eta = math.atan2(ux * cy - uy * cx, ux * cx + uy * cy)  # course left of track: > 0
            nu = -(nu1 + eta)
            self.settled = abs(xtrack) < 0.5 and abs(eta) < 0.005
        nu = max(-math.pi / 2, min(math.pi / 2, nu))
        k = 4.0 * L1_DAMPING * L1_DAMPING
        return k * v / l1 * math.sin(nu)

    def _circle(self, centre: tuple, radius: float, direction: int) -> float:
        """Turn rate holding a circle: the tangent's course plus an intercept angle."""
        s, v = self.s, self._ground_speed()
        l1 = L1_DAMPING * L1_PERIOD_S * v / math.pi
        rx, ry = s.x - centre[0], s.y - centre[1]
        r = math.hypot(rx, ry)
        theta = math.atan2(ry, rx)
        intercept = math.atan((r - radius) / (0.5 * l1))
        want = theta + direction * (math.pi / 2 + intercept)
        err = _wrap(want - s.course)
        ff = direction * v / radius if radius > 0 and abs(r - radius) < l1 else 0.0
        return ff + 4.0 * L1_DAMPING * L1_DAMPING * v / l1 * math.sin(
            max(-math.pi / 2, min(math.pi / 2, err))
        )

    # Altitude ------------------------------------------------------------------------------
    def _climb_to(self, alt: float, feedforward: float = 0.0) -> float:
        return feedforward + (alt - self.s.z) / max(ALTITUDE_TIME_CONSTANT_S * 0.2, self.dt)

    def _glide(self, a: tuple, b: tuple, end_dist: float) -> float:
        """Climb rate on the glide slope from a's altitude to b's, reached ``end_dist`` before b."""
        s, v = self.s, self.env.airspeed
        total = math.hypot(b[0] - a[0], b[1] - a[1])
        d = math.hypot(b[0] - s.x, b[1] - s.y)
        span = total - end_dist
        if span <= 1e-6:
            return self._climb_to(b[2])
        self.min_dist = min(self.min_dist, d, total)
        progress = min(max((total - self.min_dist) / span, 0.0), 1.0)
        target = a[2] + (b[2] - a[2]) * progress
        self.alt_error = target - s.z
        slope = (b[2] - a[2]) / span
        ff = v * math.sin(math.atan(slope)) if progress < 1.0 else 0.0
        return self._climb_to(target, ff)

    # One step ------------------------------------------------------------------------------
    def tick(self) -> bool:
        """Fly one step of the active command; False when the flight is over."""
        c = self.cmds[self.k]
        assert c.pos is not None
        s = self.s
        dist = math.hypot(c.pos[0] - s.x, c.pos[1] - s.y)
        free_turn = math.isinf(self.env.max_turn_rate)
        if c.command in LOITERS:
            return self._tick_loiter(c, dist)
        if self.phase == "loiter":  # PX4 circling a waypoint for its altitude
            return self._tick_px4_alt_loiter(c, dist)
        # Track the leg prev -> c.
        acc = self._acceptance(c)
        if dist <= acc and (not self.px4 or abs(s.z - c.pos[2]) <= PX4_ALT_ACCEPTANCE_M):
            # Already there (the waypoint on A where the aircraft starts): reached at once.
            return self.reached(c, f"within {dist:.1f} m")
        climb = self._glide(self.prev, c.pos, acc if self.px4 else 0.0)
        dt = self.dt
        if free_turn:
            # No turn limit: point at the waypoint and stop on it.
            self.s = AircraftState(s.x, s.y, s.z, math.atan2(c.pos[1] - s.y, c.pos[0] - s.x), s.t)
            vz = min(max(climb, -self.env.sink_rate), self.env.climb_rate)
            vh = math.sqrt(max(self.env.airspeed**2 - vz * vz, 1e-9))
            if dist <= vh * dt:
                dt = max(dist / vh, 1e-6)
                climb = (c.pos[2] - s.z) / dt
            turn = 0.0
        else:
            turn = self._l1_line(self.prev, c.pos)
            coarse = dt * COARSE_STEPS
            if (
                self.settled
                and abs(self.alt_error) < 0.5
                and dist > 3.0 * self.env.airspeed * coarse
                and -self.env.sink_rate < climb < self.env.climb_rate
            ):
                dt = coarse
        before = self.s
        self.s = step(before, self.env, turn, climb, dt)
        f0, f1 = self._finish_line(before, c), self._finish_line(self.s, c)
        crossed = f0 < 0 <= f1
        if crossed and not free_turn:
            # The autopilot checks the finish line many times a second: stop the step on it,
            # so that the next leg starts there and not up to a step beyond (a waypoint a few
            # metres after this one would otherwise be behind the aircraft already).
            self.s = step(before, self.env, turn, climb, dt * f0 / (f0 - f1))
        self._record()
        return self._check_waypoint(c, acc, crossed)

    def _finish_line(self, s: AircraftState, c: NavCommand) -> float:
        """Signed distance (times the leg's length) of ``s`` past the finish line of the leg
        prev -> c: >= 0 once past it."""
        assert c.pos is not None
        px, py = self.prev[0], self.prev[1]
        return (s.x - c.pos[0]) * (c.pos[0] - px) + (s.y - c.pos[1]) * (c.pos[1] - py)

    def _px4_point_leg(self, c: NavCommand) -> bool:
        """PX4 has no "passed" line when the leg starts on its waypoint (previous and current
        setpoints the same: mission_block.cpp checks passing only for a segment longer than
        1e-6 m); ArduPlane counts such a waypoint passed at once (Location::line_path_proportion
        returns 1)."""
        assert c.pos is not None
        return self.px4 and math.hypot(c.pos[0] - self.prev[0], c.pos[1] - self.prev[1]) < 1e-3

    def _acceptance(self, c: NavCommand) -> float:
        if self.px4:
            return self.ap.acceptance_radius
        acp = int(c.params[1]) & 0xFF if c.command == NAV_WAYPOINT else 0
        if acp > 0:
            return float(acp)
        l1 = L1_DAMPING * L1_PERIOD_S * self.env.airspeed / math.pi
        nxt = self._next_target()
        turn = 90.0
        if nxt is not None and c.pos is not None:
            a1 = math.atan2(c.pos[1] - self.prev[1], c.pos[0] - self.prev[0])
            a2 = math.atan2(nxt[1] - c.pos[1], nxt[0] - c.pos[0])
            turn = min(abs(math.degrees(_wrap(a2 - a1))), 90.0)
        return min(self.ap.wp_radius, l1) * turn / 90.0

    def _check_waypoint(self, c: NavCommand, acc: float, crossed: bool = False) -> bool:
        s = self.s
        assert c.pos is not None
        dist = math.hypot(c.pos[0] - s.x, c.pos[1] - s.y)
        passed = crossed or (self._finish_line(s, c) >= 0 and not self._px4_point_leg(c))
        horizontal = dist <= acc or passed
        if not horizontal:
            return True
        if c.command == NAV_LAND:
            self._event(c.seq, "reached", "landing")
            self.ended = "landing"
            return False
        dz = abs(s.z - c.pos[2])
        if self.px4 and dz > PX4_ALT_ACCEPTANCE_M:
            if self.phase != "loiter":
                self.phase = "loiter"
                self._event(c.seq, "altitude", f"{dz:.0f} m off its altitude: circling it")
            return True
        how = f"within {dist:.1f} m" if dist <= acc else f"passed at {dist:.1f} m"
        return self.reached(c, how)

    def _tick_px4_alt_loiter(self, c: NavCommand, dist: float) -> bool:
        assert c.pos is not None
        radius, direction = self._loiter_geometry(NavCommand(c.seq, NAV_WAYPOINT, c.pos, c.params))
        turn = self._circle(c.pos, radius, direction)
        self.s = step(self.s, self.env, turn, self._climb_to(c.pos[2]), self.dt)
        self._record()
        if abs(self.s.z - c.pos[2]) > PX4_ALT_ACCEPTANCE_M:
            return True
        if not self._exit_heading(c, PX4_EXIT_HEADING_DEG, 0.0):
            return True
        return self.reached(c, "altitude reached circling it")

    def _exit_heading(self, c: NavCommand, tolerance_deg: float, laps: float) -> bool:
        """The course points at the next waypoint (or there is none, or it is inside the
        circle): the loiter may end."""
        nxt = self._next_target()
        if nxt is None or c.pos is None:
            return True
        radius, _ = self._loiter_geometry(c)
        if math.hypot(nxt[0] - c.pos[0], nxt[1] - c.pos[1]) < 1.2 * radius:
            return True
        bearing = math.atan2(nxt[1] - self.s.y, nxt[0] - self.s.x)
        tol = math.radians(tolerance_deg * (1 + (int(laps) if not self.px4 else 0)))
        return abs(_wrap(bearing - self.s.course)) <= tol

    def _px4_tangent_exit(self, c: NavCommand, radius: float, direction: int) -> tuple | None:
        """Where PX4 starts the next leg after a loiter left with param4 (xtrack) set: the point
        of the circle whose tangent, in the loiter's sense, passes through the next waypoint,
        computed from the centre (mission_block.cpp, is_mission_item_reached), not where the
        aircraft is. A next waypoint on or inside the circle gives the point of the circle
        towards it."""
        assert c.pos is not None
        nxt = self._next_target()
        if nxt is None:
            return None
        rng = math.hypot(nxt[0] - c.pos[0], nxt[1] - c.pos[1])
        if rng < 1e-6:
            return None
        inner = math.acos(min(radius / rng, 1.0))
        a = math.atan2(nxt[1] - c.pos[1], nxt[0] - c.pos[0]) - direction * inner
        return (c.pos[0] + radius * math.cos(a), c.pos[1] + radius * math.sin(a), c.pos[2])

    def _tick_loiter(self, c: NavCommand, dist: float) -> bool:
        assert c.pos is not None
        radius, direction = self._loiter_geometry(c)
        on_circle = abs(dist - radius) <= max(0.1 * radius, 5.0)
        if self.phase == "track" and dist > radius + max(0.1 * radius, 5.0):
            turn = (
                self._l1_line(self.prev, c.pos)
                if dist > 2 * radius
                else self._circle(c.pos, radius, direction)
            )
        else:
            turn = self._circle(c.pos, radius, direction)
        if self.px4 and c.command == NAV_LOITER_TO_ALT and self.hold_alt is not None:
            if dist <= radius + self.ap.acceptance_radius:
                self.hold_alt = None
            climb = self._climb_to(self.hold_alt if self.hold_alt is not None else c.pos[2])
        elif self.phase == "track" and dist > 2 * radius and not self.px4:
            climb = self._glide(self.prev, c.pos, radius)
        else:
            climb = self._climb_to(c.pos[2])
        before = self.s.course
        self.s = step(self.s, self.env, turn, climb, self.dt)
        self._record()
        if on_circle or self.loiter_started:
            if not self.loiter_started:
                self.loiter_started = True
                self.loiter_t0 = self.s.t
                self.phase = "loiter"
            self.loiter_sum += direction * _wrap(self.s.course - before)
        if not self.loiter_started:
            return True
        if c.command == NAV_LOITER_UNLIM:
            self._event(c.seq, "reached", "loitering")
            self.ended = "loiter at end"
            return False
        laps = self.loiter_sum / (2 * math.pi)
        dz = abs(self.s.z - c.pos[2])
        if self.px4:
            done = dz <= PX4_ALT_ACCEPTANCE_M and not (
                c.command == NAV_LOITER_TIME and self.s.t - self.loiter_t0 < c.params[0]
            )
            # force_heading: param1 of LOITER_TO_ALT, param2 of LOITER_TIME (mavlink_mission.cpp)
            heading = (c.params[0] if c.command == NAV_LOITER_TO_ALT else c.params[1]) > 0
            tol = PX4_EXIT_HEADING_DEG
        else:
            if c.command == NAV_LOITER_TURNS:
                done = laps >= max(float(c.params[0]), 0.0)
            elif c.command == NAV_LOITER_TO_ALT:
                done = dz <= ARDUPLANE_LOITER_ALT_M
            else:
                done = self.s.t - self.loiter_t0 >= c.params[0]
            heading = True
            tol = ARDUPLANE_EXIT_HEADING_DEG
        if not done:
            return True
        if heading and not self._exit_heading(c, tol, laps):
            return True
        exit_from = None
        if c.params[3] > 0:
            exit_from = (
                self._px4_tangent_exit(c, radius, direction)
                if self.px4
                else (self.s.x, self.s.y, self.s.z)
            )
        how = f"after {laps:.2f} turns, {dz:.1f} m from its altitude"
        return self.reached(c, how, exit_from)


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
) -> Flight:
    """Fly the stored ``items`` in mode AUTO from ``start`` (local frame) with ``profile``'s
    envelope, in fast-forward time with a fixed step ``dt``.

    ``course`` is the heading at the start (rad, counter-clockwise from east), by default
    towards the first item that is not a loiter. ``time_limit`` (s) stops an aircraft that never
    finishes, by default three times the time to fly the items' chords plus ten minutes.
    """
    ap = params or AutopilotParams(flavour=flavour, loiter_radius=profile.turn_radius)
    base_alt = float(start[2] + frame.origin.alt) if home_alt is None else home_alt
    cmds = nav_commands(items, frame, base_alt, home_at_seq0=home_at_seq0)
    positions = [c.pos for c in cmds if c.pos is not None]
    if course is None:
        # A loiter's position is its centre, off the path: aim at the first other item, so an
        # aircraft that starts a helix at A is on its circle's tangent (the planner's free
        # heading at A).
        course = 0.0
        aims = [c.pos for c in cmds if c.pos is not None and c.command not in LOITERS]
        for p in aims or positions:
            if math.hypot(p[0] - start[0], p[1] - start[1]) > 1.0:
                course = math.atan2(p[1] - start[1], p[0] - start[0])
                break
    if time_limit is None:
        pts = [start, *positions]
        chords = sum(math.dist(p, q) for p, q in zip(pts, pts[1:], strict=False))
        time_limit = 3.0 * chords / profile.cruise_airspeed + 600.0
    s0 = AircraftState(float(start[0]), float(start[1]), float(start[2]), course)
    pilot = _Autopilot(cmds, profile, ap, s0, dt)
    pilot._record()
    going = pilot.advance()
    while going:
        if pilot.s.t >= time_limit:
            pilot.ended = "time limit"
            pilot._event(pilot.cmds[pilot.k].seq, "end", f"still flying after {time_limit:.0f} s")
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
    )


def turn_radius_flown(bank_deg: float, airspeed: float) -> float:
    """Radius of a coordinated turn at ``bank_deg`` (inf when wings level)."""
    t = math.tan(math.radians(abs(bank_deg)))
    return math.inf if t < 1e-12 else airspeed * airspeed / (G * t)
