"""PX4's mission logic for a fixed wing (PX4-Autopilot main, read for this module; modelled, not
copied).

* A NAV_WAYPOINT is reached (mission_block.cpp, MissionBlock::is_mission_item_reached_or_
  completed) within the navigator's acceptance radius horizontally, or once past the waypoint
  along the previous-to-current line (checked only for a segment longer than 1e-6 m), AND within
  NAV_FW_ALT_RAD (10 m) of its altitude; param2 counts for multicopters only. The acceptance
  radius is max(NAV_ACC_RAD, the path controller's switch distance) (navigator_main.cpp,
  Navigator::get_acceptance_radius takes position_controller_status.acceptance_radius when
  larger; FixedwingPositionControl publishes _npfg.switchDistance(500)), and the switch distance
  is min(500 m, NPFG_SW_DST_MLT * track error bound), the bound being the ground speed times the
  time constant NPFG_PERIOD * NPFG_DAMPING (npfg.cpp NPFG::switchDistance, trackErrorBound,
  timeConst): 10 * 0.7 * 0.32 * 25 = 56 m at 25 m/s with the defaults. So a fixed-wing PX4
  turns for the next waypoint about 2.3 s of ground speed early, whatever NAV_ACC_RAD says.
* An aircraft that comes to the waypoint too high or too low circles it on NAV_LOITER_RAD until
  the altitude is in (the position setpoint turned into a loiter), then leaves with its course on
  the next waypoint. The altitude target slides linearly to the waypoint's and reaches it
  max(acceptance radius, |loiter radius|) before the waypoint, NAV_LOITER_RAD for a waypoint
  without its own (FixedwingPositionControl::control_auto_position, the altitude first-order
  hold; mission_block.cpp mission_item_to_position_setpoint fills the loiter radius).
* Leaving a loiter on a course (the altitude loiter of a waypoint, or LOITER_TO_ALT / LOITER_TIME
  with heading required): the ground velocity within 5 degrees of the bearing to the next
  waypoint (mission_block.h kCosineExitCourseThreshold = cos 5 deg), enforced only when the next
  waypoint is farther than 1.05 loiter radii from the centre (is_mission_item_reached_or_
  completed, exit_course_is_reachable).
* LOITER_TO_ALT (mavlink_mission.cpp: param1 heading required, param2 the signed radius, param4
  cross-track exit) keeps the current altitude until within the acceptance radius plus the
  loiter radius of the centre, then climbs or sinks to the item's; reached within NAV_FW_ALT_RAD,
  wherever on the circle (no turns counted). With param4 > 0 the next leg starts at the tangent
  point PX4 computes from the centre towards the next waypoint, not where the aircraft is.
  LOITER_TIME: param2 heading required, param3 the radius.
* LOITER_TURNS is not a position item in PX4's navigator (item_contains_position): it is
  skipped, as are DO items other than DO_CHANGE_SPEED.
"""

from __future__ import annotations

import math

from gcs_planner.sim.navigators.base import Navigator
from gcs_planner.sim.navigators.commands import (
    NAV_LOITER_TIME,
    NAV_LOITER_TO_ALT,
    NAV_LOITER_TURNS,
    NavCommand,
)

from gcs_planner.aircraft.autopilot import PX4

ALTITUDE_ACCEPTANCE_M = 10.0  # NAV_FW_ALT_RAD
EXIT_COURSE_DEG = 5.0  # kCosineExitCourseThreshold
EXIT_REACHABLE = 1.05  # exit_course_is_reachable
SWITCH_DISTANCE_CAP_M = 500.0  # FixedwingPositionControl: _npfg.switchDistance(500.0f)


class PX4Navigator(Navigator):
    autopilot = PX4
    flavour = PX4.firmware
    _held_for = -1  # seq of the LOITER_TO_ALT whose approach altitude is held

    def switch_distance(self) -> float:
        """npfg's switch distance at the current ground speed (see the module docstring)."""
        vg = self.ground_speed()
        time_const = self.ap.npfg_period * self.ap.npfg_damping
        bound = vg * time_const if vg > 1.0 else 0.5 * time_const * (vg * vg + 1.0)
        return min(SWITCH_DISTANCE_CAP_M, bound * self.ap.npfg_switch_multiplier)

    def acceptance(self, c: NavCommand) -> float:
        return max(self.ap.acceptance_radius, self.switch_distance())

    def skips(self, c: NavCommand) -> str:
        if c.command == NAV_LOITER_TURNS:
            return "LOITER_TURNS is not a PX4 position item"
        return ""

    def point_leg_without_finish_line(self, c: NavCommand) -> bool:
        assert c.pos is not None
        return math.hypot(c.pos[0] - self.prev[0], c.pos[1] - self.prev[1]) < 1e-3

    def glide_end(self, acceptance: float) -> float:
        return max(acceptance, abs(self.ap.loiter_radius))

    def waypoint_altitude_ok(self, dz: float) -> bool:
        return dz <= ALTITUDE_ACCEPTANCE_M

    def loiter_done(self, c: NavCommand, laps: float, dz: float) -> bool:
        if c.command == NAV_LOITER_TIME and self.s.t - self.loiter_t0 < c.params[0]:
            return False
        return dz <= ALTITUDE_ACCEPTANCE_M

    def exit_heading_ok(self, c: NavCommand, laps: float) -> bool:
        # force_heading: param1 of LOITER_TO_ALT, param2 of LOITER_TIME (mavlink_mission.cpp);
        # the altitude loiter of a waypoint always leaves on the course.
        if c.command == NAV_LOITER_TO_ALT:
            required = c.params[0] > 0
        elif c.command == NAV_LOITER_TIME:
            required = c.params[1] > 0
        else:
            required = True
        if not required:
            return True
        radius, _ = self.loiter_geometry(c)
        return self.course_lined_up(c, EXIT_COURSE_DEG, EXIT_REACHABLE, radius)

    def exit_point(self, c: NavCommand, radius: float, direction: int) -> tuple | None:
        """The point of the circle whose tangent, in the loiter's sense, passes through the next
        waypoint, computed from the centre (mission_block.cpp), not where the aircraft is. A next
        waypoint on or inside the circle gives the point of the circle towards it."""
        assert c.pos is not None
        nxt = self.next_target()
        if nxt is None:
            return None
        rng = math.hypot(nxt[0] - c.pos[0], nxt[1] - c.pos[1])
        if rng < 1e-6:
            return None
        inner = math.acos(min(radius / rng, 1.0))
        a = math.atan2(nxt[1] - c.pos[1], nxt[0] - c.pos[0]) - direction * inner
        return (c.pos[0] + radius * math.cos(a), c.pos[1] + radius * math.sin(a), c.pos[2])

    def loiter_approach_climb(self, c: NavCommand, dist: float, radius: float) -> float | None:
        if c.command != NAV_LOITER_TO_ALT:
            return None
        assert c.pos is not None
        if self._held_for != c.seq:
            self._held_for = c.seq
            self.hold_alt = self.est[2]
        if self.hold_alt is not None and dist <= radius + self.acceptance(c):
            self.hold_alt = None
        return self.climb_to(self.hold_alt if self.hold_alt is not None else c.pos[2])
