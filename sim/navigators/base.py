"""What every fixed-wing navigator in mode AUTO does alike: the mission sequence, L1-type
lateral guidance on the ground velocity, circling, the altitude target, one step of flight.

The rules where ArduPlane and PX4 differ (when a waypoint is reached, where the altitude ramp
ends, how a loiter is sized, finished and left) are hooks each autopilot's navigator fills
(sim/navigators/arduplane.py, sim/navigators/px4.py), so each rule lives in one place.

Lateral guidance is L1 (Park, Deyst, How 2004) as ArduPlane's AP_L1_Control::update_waypoint
computes it, on the GROUND velocity (its _groundspeed_vector): lateral acceleration
K Vg^2 / L1 sin(Nu), K = 4 damping^2, L1 = damping period Vg / pi (NAVL1_PERIOD 17 s,
NAVL1_DAMPING 0.75), Nu the intercept angle asin(xtrack / L1) (limited to 45 degrees) plus the
track-angle error of the ground course; behind the previous waypoint and farther than L1 from it
the aircraft heads for it first (sim/navigators/steering.py). PX4's npfg follows the line with
the same structure on the ground velocity too (npfg.cpp NPFG::guideToPath); its own gains are
not modelled, its switch distance is (sim/navigators/px4.py).

What the navigator holds over a flight (the state, the estimate it steers, the track) is
sim/navigators/state.py; the mission's words sim/navigators/commands.py.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import ClassVar

from gcs_planner.sim.navigators import steering
from gcs_planner.sim.navigators.airframe import POINT_MASS, Airframe, PointMass
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
from gcs_planner.sim.navigators.params import DEFAULT_TIME_CONSTANT_S
from gcs_planner.sim.navigators.state import (
    COARSE_STEPS,
    DEFAULT_STEP_S,
    SAMPLE_FIELDS,
    NavigatorState,
)
from gcs_planner.sim.navigators.steering import L1_DAMPING, L1_PERIOD_S, wrap

from gcs_planner.aircraft.autopilot import Autopilot

# The names this module has been read by (the mission's words, the airframe, the guidance).
__all__ = [
    "ALTITUDE_TIME_CONSTANT_S", "COARSE_STEPS", "DEFAULT_STEP_S", "DO_CHANGE_SPEED",
    "L1_DAMPING", "L1_PERIOD_S", "LOITERS", "NAV_LAND", "NAV_LOITER_TIME", "NAV_LOITER_TO_ALT",
    "NAV_LOITER_TURNS", "NAV_LOITER_UNLIM", "NAV_RETURN_TO_LAUNCH", "NAV_TAKEOFF", "NAV_WAYPOINT",
    "POINT_MASS", "SAMPLE_FIELDS", "Airframe", "Event", "NavCommand", "Navigator",
    "NavigatorFactory", "PointMass", "wrap",
]  # fmt: skip

# TECS altitude time constant (ArduPlane TECS_TIME_CONST, PX4 FW_T_ALT_TC) as both ship it: 5 s.
# The navigator flies its autopilot's own (AutopilotParams.altitude_time_constant).
ALTITUDE_TIME_CONSTANT_S = DEFAULT_TIME_CONSTANT_S


class Navigator(NavigatorState):
    """Mode AUTO over one flight. Subclasses are the autopilots: ``autopilot`` is the record of
    the one each flies as (gcs_planner/aircraft/autopilot.py), ``flavour`` its name."""

    autopilot: ClassVar[Autopilot]
    flavour: ClassVar[str] = ""

    # Hooks: each autopilot's rules --------------------------------------------------------
    def acceptance(self, c: NavCommand) -> float:
        """Horizontal distance within which waypoint ``c`` counts as reached."""
        raise NotImplementedError

    def skips(self, c: NavCommand) -> str:
        """Why this autopilot does not fly item ``c`` as a position ("" when it does)."""
        return ""

    def point_leg_without_finish_line(self, c: NavCommand) -> bool:
        """A leg starting on its own waypoint has no "passed" line on this autopilot."""
        return False

    def glide_end(self, acceptance: float) -> float:
        """How far before the waypoint the altitude ramp reaches the waypoint's altitude."""
        return 0.0

    def waypoint_altitude_ok(self, dz: float) -> bool:
        """A waypoint reached horizontally ``dz`` m off its altitude counts as reached."""
        return True

    def loiter_radius(self, radius: float) -> float:
        """The radius the autopilot circles for a commanded ``radius``, here and now."""
        return radius

    def loiter_done(self, c: NavCommand, laps: float, dz: float) -> bool:
        raise NotImplementedError

    def exit_heading_ok(self, c: NavCommand, laps: float) -> bool:
        raise NotImplementedError

    def exit_point(self, c: NavCommand, radius: float, direction: int) -> tuple | None:
        """Where the next leg starts after loiter ``c`` (None: at the loiter's position)."""
        return None

    def loiter_approach_climb(self, c: NavCommand, dist: float, radius: float) -> float | None:
        """The climb rate on the way to a loiter, or None for "climb to its altitude"."""
        return None

    def on_loiter_started(self, c: NavCommand) -> None:
        """Called once when the aircraft is on the loiter's circle."""

    # The mission sequence -----------------------------------------------------------------
    def flies(self, c: NavCommand) -> bool:
        """Whether the autopilot flies item ``c`` as a position (or ends the flight at it)."""
        if c.command == NAV_RETURN_TO_LAUNCH:
            return True
        if c.pos is None or self.skips(c):
            return False
        return c.command in (NAV_WAYPOINT, NAV_TAKEOFF, NAV_LAND) or c.command in LOITERS

    def next_nav_index(self, start: int) -> int | None:
        """The index of the first command from ``start`` on that the autopilot flies."""
        for j in range(start, len(self.cmds)):
            if self.flies(self.cmds[j]):
                return j
        return None

    def next_target(self) -> tuple[float, float, float] | None:
        j = self.next_nav_index(self.k + 1)
        return None if j is None else self.cmds[j].pos

    def advance(self) -> bool:
        """Make the next command active; run the DO items on the way. False at the end."""
        j = self.k + 1
        while j < len(self.cmds):
            c = self.cmds[j]
            if self.flies(c):
                break
            why = self.skips(c)
            if c.command == DO_CHANGE_SPEED and c.params[1] > 0:
                speed = self.ap.commanded_airspeed(c.params[1])
                if speed is None:
                    why = (
                        f"DO_CHANGE_SPEED {c.params[1]:g} m/s lies outside AIRSPEED_MIN.."
                        f"AIRSPEED_MAX {self.ap.airspeed_min:g}..{self.ap.airspeed_max:g}: "
                        f"ignored, the aircraft stays at {self.env.airspeed:g} m/s"
                    )
                    self.notes.append(f"item {c.seq}: {why}")
                    self.event(c.seq, "skipped", why)
                else:
                    self.env = self._envelope(speed)
            elif why:
                self.notes.append(f"item {c.seq}: {why}; skipped")
                self.event(c.seq, "skipped", why)
            elif c.command != DO_CHANGE_SPEED:
                self.event(c.seq, "skipped")
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
        # ArduPlane set_next_WP: already past the new leg's finish line, track it from here.
        ex, ey, ez = self.est
        px, py = self.prev[0], self.prev[1]
        if (ex - c.pos[0]) * (c.pos[0] - px) + (ey - c.pos[1]) * (c.pos[1] - py) > 0:
            self.prev = (ex, ey, ez)
        return True

    def reached(self, c: NavCommand, how: str, exit_from: tuple | None = None) -> bool:
        assert c.pos is not None
        self.event(c.seq, "reached", how)
        self.prev = exit_from or c.pos
        return self.advance()

    def loiter_geometry(self, c: NavCommand) -> tuple[float, int]:
        """(radius flown, direction: +1 counter-clockwise, -1 clockwise) of a loiter item. The
        signed radius is param3 of the loiters, but param2 of LOITER_TO_ALT (common.xml; PX4's
        mavlink_mission.cpp and ArduPilot's AP_Mission read it there); 0 takes the autopilot's
        loiter radius parameter. The aircraft cannot hold a circle tighter than its roll limit
        allows at its true airspeed."""
        p = c.params[1] if c.command == NAV_LOITER_TO_ALT else c.params[2]
        signed = p if abs(p) > 0 and c.command != NAV_WAYPOINT else self.ap.loiter_radius
        radius = self.loiter_radius(abs(signed))
        radius = max(radius, self.env.min_radius(self.s.tas))
        return radius, (-1 if signed >= 0 else 1)

    # Lateral guidance ---------------------------------------------------------------------
    def l1_line(self, a: tuple, b: tuple) -> float:
        """Lateral acceleration (m/s^2, + left) of L1 guidance on the line a -> b."""
        lateral, self.settled = steering.l1_line(self.est, self.s.course, self.ground_speed(), a, b)
        return lateral

    def circle(self, centre: tuple, radius: float, direction: int) -> float:
        """Lateral acceleration holding a circle: the centripetal term of the ground speed plus
        L1 on the tangent's course with an intercept angle."""
        return steering.circle(
            self.est, self.s.course, self.ground_speed(), centre, radius, direction
        )

    # Altitude -----------------------------------------------------------------------------
    def climb_to(self, alt: float, feedforward: float = 0.0) -> float:
        """The climb rate TECS asks for to reach ``alt`` (m) from the estimate: the demand's own
        rate plus the height error over its time constant (ArduPlane AP_TECS::_update_pitch,
        SEBdot_dem = hgt_rate_dem g + SEB_error / timeConstant(); PX4 TECS.cpp
        _calcAltitudeControlOutput, the error times 1 / FW_T_ALT_TC plus the rate setpoint)."""
        return feedforward + (alt - self.est[2]) / self._altitude_gain_dt()

    def _altitude_gain_dt(self) -> float:
        """The time over which climb_to asks to fly out an altitude error: the autopilot's
        TECS time constant (TECS_TIME_CONST, FW_T_ALT_TC), at least a step."""
        tc = self.ap.altitude_time_constant or ALTITUDE_TIME_CONSTANT_S
        return max(tc, self.dt)

    def glide(self, a: tuple, b: tuple, end_dist: float) -> float:
        """Climb rate on the glide slope from a's altitude to b's, reached ``end_dist`` before b;
        the slope is over the ground, so its feed-forward rate is the ground speed's."""
        x, y, z = self.est
        total = math.hypot(b[0] - a[0], b[1] - a[1])
        d = math.hypot(b[0] - x, b[1] - y)
        span = total - end_dist
        if span <= 1e-6:
            return self.climb_to(b[2])
        self.min_dist = min(self.min_dist, d, total)
        progress = min(max((total - self.min_dist) / span, 0.0), 1.0)
        target = a[2] + (b[2] - a[2]) * progress
        self.alt_error = target - z
        slope = (b[2] - a[2]) / span
        # No feed-forward before the ramp starts: the target holds the previous waypoint's
        # altitude until the aircraft is abeam of it (PX4 FixedwingPositionControl
        # control_auto_position, the altitude first-order hold on _min_current_sp_distance_xy;
        # ArduPlane's glide slope at line_path_proportion 0), and a constant target gives TECS
        # no rate to feed forward. (A PX4 that switched 56 m early used to start the next
        # climb before the landmark and pass it 4-6 m high.)
        ff = self.ground_speed() * slope if 0.0 < progress < 1.0 else 0.0
        return self.climb_to(target, ff)

    # One step -----------------------------------------------------------------------------
    def finish_line(self, p: tuple, c: NavCommand) -> float:
        """Signed distance (times the leg's length) of point ``p`` past the finish line of the
        leg prev -> c: >= 0 once past it."""
        assert c.pos is not None
        px, py = self.prev[0], self.prev[1]
        return (p[0] - c.pos[0]) * (c.pos[0] - px) + (p[1] - c.pos[1]) * (c.pos[1] - py)

    def tick(self) -> bool:
        """Fly one step of the active command; False when the flight is over."""
        c = self.cmds[self.k]
        assert c.pos is not None
        x, y, z = self.est
        dist = math.hypot(c.pos[0] - x, c.pos[1] - y)
        if c.command in LOITERS:
            return self._tick_loiter(c, dist)
        if self.phase == "loiter":  # PX4 circling a waypoint for its altitude
            return self._tick_altitude_loiter(c)
        acc = self.acceptance(c)
        if dist <= acc and self.waypoint_altitude_ok(abs(z - c.pos[2])):
            # Already there (the waypoint on A where the aircraft starts): reached at once.
            return self.reached(c, f"within {dist:.1f} m")
        climb = self.glide(self.prev, c.pos, self.glide_end(acc))
        dt = self.dt
        heading = None
        lateral = 0.0
        if self.free_turn:
            # No turn limit: point the ground track at the waypoint and stop on its acceptance
            # circle. The flight between is a straight line: in steady air a long step flies it
            # as exactly as short ones (the INS finds passes on the segments).
            if self.steady_air:
                dt *= 4 * COARSE_STEPS
            heading, dt, climb = self._free_turn_step(c, dist, climb, dt, acc)
        else:
            lateral = self.l1_line(self.prev, c.pos)
            coarse = dt * COARSE_STEPS
            if (
                self.settled
                and self.airframe.exact
                and self.steady_air
                and abs(self.alt_error) < 0.5
                and dist > 3.0 * self.ground_speed() * coarse
                and -self.env.sink_rate < climb < self.env.climb_rate
            ):
                dt = coarse
                # The altitude error flown out over the coarse step as the fine steps would
                # (the share 1 - e^(-coarse / time constant)), not the fine step's rate held over
                # it: that overshot the target, then fine steps flew back: ~1 m wiggles a minute
                # on a long climbing leg, 1e-4 of its length once the aircraft rolls into its
                # turns and switches between coarse and fine steps more often.
                gain = self._altitude_gain_dt()
                climb += self.alt_error * (-math.expm1(-coarse / gain) / coarse - 1.0 / gain)
        before, est0 = self.s, self.est
        wind = self.air(dt)
        e2t = self.eas2tas(before.z)
        self.s = self.airframe.step(before, self.env, lateral, climb, dt, wind, e2t, heading)
        off = (est0[0] - before.x, est0[1] - before.y)
        f0 = self.finish_line(est0, c)
        f1 = self.finish_line((self.s.x + off[0], self.s.y + off[1]), c)
        crossed = f0 < 0 <= f1
        if crossed and not self.free_turn and self.airframe.exact:
            # The autopilot checks the finish line many times a second: stop the step on it,
            # so that the next leg starts there and not up to a step beyond. (A flight model
            # that cannot fly a step again from its start flies its inner steps on: the next
            # leg starts up to one outer step beyond.)
            cut = dt * f0 / (f0 - f1)
            self.s = self.airframe.step(before, self.env, lateral, climb, cut, wind, e2t)
        self._after(before)
        self.record()
        return self._check_waypoint(c, acc, crossed)

    def _free_turn_step(
        self, c: NavCommand, dist: float, climb: float, dt: float, acc: float = 0.0
    ) -> tuple[float, float, float]:
        """(heading, step, climb) of an aircraft without turn limit: the heading whose ground
        track points at the waypoint in the current wind, the step cut to land on its
        acceptance circle (on the waypoint for an acceptance under a metre)."""
        assert c.pos is not None
        x, y, z = self.est
        bearing = math.atan2(c.pos[1] - y, c.pos[0] - x)
        wx, wy = self.wind.current() if self.wind is not None else (0.0, 0.0)
        tas = self.env.airspeed * self.eas2tas(z)
        vz = self.env.climb_through_air(climb, tas)
        vh = math.sqrt(max(tas * tas - vz * vz, 1e-9))
        cross = -wx * math.sin(bearing) + wy * math.cos(bearing)
        heading = bearing - math.asin(max(-1.0, min(1.0, cross / vh)))
        along = vh * math.cos(heading - bearing) + wx * math.cos(bearing) + wy * math.sin(bearing)
        # Stop on the waypoint, or a centimetre inside a wider acceptance circle.
        stop = dist if acc < 1.0 + 1e-9 else max(dist - acc + 0.01, 0.0)
        if along > 0 and stop <= along * dt:
            dt = max(stop / along, 1e-6)
        # A straight leg is a straight line to the waypoint in 3D: the rate that arrives at its
        # altitude (clipped to the autopilot's rates by the aircraft).
        if along > 0:
            climb = (c.pos[2] - z) * along / max(dist, 1e-6)
        return heading, dt, climb

    def _check_waypoint(self, c: NavCommand, acc: float, crossed: bool = False) -> bool:
        assert c.pos is not None
        x, y, z = self.est
        dist = math.hypot(c.pos[0] - x, c.pos[1] - y)
        passed = crossed or (
            self.finish_line(self.est, c) >= 0 and not self.point_leg_without_finish_line(c)
        )
        if not (dist <= acc or passed):
            return True
        if c.command == NAV_LAND:
            self.event(c.seq, "reached", "landing")
            self.ended = "landing"
            return False
        dz = abs(z - c.pos[2])
        if not self.waypoint_altitude_ok(dz):
            if self.phase != "loiter":
                self.phase = "loiter"
                self.event(c.seq, "altitude", f"{dz:.0f} m off its altitude: circling it")
            return True
        how = f"within {dist:.1f} m" if dist <= acc else f"passed at {dist:.1f} m"
        return self.reached(c, how)

    def _tick_altitude_loiter(self, c: NavCommand) -> bool:
        assert c.pos is not None
        radius, direction = self.loiter_geometry(NavCommand(c.seq, NAV_WAYPOINT, c.pos, c.params))
        self._fly(self.circle(c.pos, radius, direction), self.climb_to(c.pos[2]), self.dt)
        self.record()
        if not self.waypoint_altitude_ok(abs(self.est[2] - c.pos[2])):
            return True
        if not self.exit_heading_ok(c, 0.0):
            return True
        return self.reached(c, "altitude reached circling it")

    def _tick_loiter(self, c: NavCommand, dist: float) -> bool:
        assert c.pos is not None
        radius, direction = self.loiter_geometry(c)
        band = max(0.1 * radius, 5.0)
        on_circle = abs(dist - radius) <= band
        if self.phase == "track" and dist > radius + band:
            lateral = (
                self.l1_line(self.prev, c.pos)
                if dist > 2 * radius
                else self.circle(c.pos, radius, direction)
            )
        else:
            lateral = self.circle(c.pos, radius, direction)
        climb = self.loiter_approach_climb(c, dist, radius)
        if climb is None:
            climb = self.climb_to(c.pos[2])
        before = self.s.course
        self._fly(lateral, climb, self.dt)
        self.record()
        if on_circle or self.loiter_started:
            if not self.loiter_started:
                self.loiter_started = True
                self.loiter_t0 = self.s.t
                self.phase = "loiter"
                self.on_loiter_started(c)
            self.loiter_sum += direction * wrap(self.s.course - before)
        if not self.loiter_started:
            return True
        if c.command == NAV_LOITER_UNLIM:
            self.event(c.seq, "reached", "loitering")
            self.ended = "loiter at end"
            return False
        laps = self.loiter_sum / (2 * math.pi)
        dz = abs(self.est[2] - c.pos[2])
        if not self.loiter_done(c, laps, dz):
            return True
        if not self.exit_heading_ok(c, laps):
            return True
        exit_from = self.exit_point(c, radius, direction) if c.params[3] > 0 else None
        how = f"after {laps:.2f} turns, {dz:.1f} m from its altitude"
        return self.reached(c, how, exit_from)

    # Shared exit-course test --------------------------------------------------------------
    def course_lined_up(
        self, c: NavCommand, tolerance_deg: float, reachable: float, radius: float
    ) -> bool:
        """The ground course points at the next waypoint within ``tolerance_deg``, or the next
        waypoint is within ``reachable`` radii of the centre (the course can never point at it)
        or there is none."""
        nxt = self.next_target()
        if nxt is None or c.pos is None:
            return True
        if math.hypot(nxt[0] - c.pos[0], nxt[1] - c.pos[1]) <= reachable * radius:
            return True
        bearing = math.atan2(nxt[1] - self.est[1], nxt[0] - self.est[0])
        return abs(wrap(bearing - self.s.course)) <= math.radians(tolerance_deg)


NavigatorFactory = Callable[..., Navigator]
