"""ArduPlane's mission logic in mode AUTO (ArduPlane 4.x sources, read for this module; modelled,
not copied).

* A NAV_WAYPOINT is reached (commands_logic.cpp, Plane::verify_nav_wp) within its acceptance
  radius param2 (whole metres, 0..255) or, when param2 is 0, within the L1 turn distance
  (AP_L1_Control::turn_distance(wp_radius, turn_angle): min(WP_RADIUS * EAS2TAS^2, L1) scaled
  by the turn to the next leg / 90 degrees); or once past the finish line, the perpendicular to
  the track through the waypoint. Altitude is not checked: the target slides from the previous
  waypoint's altitude to this one's in proportion to the distance flown and is reached at the
  waypoint (Plane::setup_glide_slope, "glide slope"); a waypoint the aircraft could not climb to
  is passed all the same. The next leg starts at the reached waypoint, or at the aircraft when
  it is already past the new leg's finish line (Plane::set_next_WP).
* Every loiter radius is scaled to the altitude (AP_L1_Control::loiter_radius): with
  NAVL1_LIM_BANK = 0, the default, radius * EAS2TAS^2; otherwise at least the radius the bank
  limit gives at the target airspeed, scaled.
* LOITER_TURNS counts param1 turns once on the circle (Plane::verify_loiter_turns); LOITER_TO_ALT
  circles until the altitude is within 5 m (Plane::verify_loiter_to_alt); LOITER_TIME for param1
  seconds (Plane::verify_loiter_time). Each then leaves once the ground course points at the next
  waypoint within 10 degrees plus 10 per full lap flown, or at once when the next waypoint is
  within 1.05 WP_LOITER_RAD of the centre (Plane::verify_loiter_heading, mode_loiter.cpp
  ModeLoiter::isHeadingLinedUp and isHeadingLinedUp_cd: the course is the ground-speed vector's
  angle). With param4 (xtrack) > 0 the next leg is tracked from the exit point, otherwise from
  the loiter's centre. On the way to a loiter far away the glide slope runs to its circle.
"""

from __future__ import annotations

import math

from gcs_planner.sim.navigators.base import Navigator
from gcs_planner.sim.navigators.commands import (
    NAV_LOITER_TO_ALT,
    NAV_LOITER_TURNS,
    NAV_WAYPOINT,
    NavCommand,
)
from gcs_planner.sim.navigators.steering import L1_DAMPING, L1_PERIOD_S, wrap

from gcs_planner.aircraft.autopilot import ARDUPLANE
from gcs_planner.aircraft.profile import G

LOITER_ALTITUDE_M = 5.0  # verify_loiter_to_alt
EXIT_COURSE_DEG = 10.0  # isHeadingLinedUp_cd: 10 degrees, + 10 per lap
EXIT_REACHABLE = 1.05  # isHeadingLinedUp: next waypoint within 1.05 WP_LOITER_RAD


class ArduPlaneNavigator(Navigator):
    autopilot = ARDUPLANE
    flavour = ARDUPLANE.firmware

    def acceptance(self, c: NavCommand) -> float:
        acp = int(c.params[1]) & 0xFF if c.command == NAV_WAYPOINT else 0
        if acp > 0:
            return float(acp)
        e2t = self.eas2tas(self.s.z)
        l1 = L1_DAMPING * L1_PERIOD_S * self.ground_speed() / math.pi
        nxt = self.next_target()
        turn = 90.0
        if nxt is not None and c.pos is not None:
            a1 = math.atan2(c.pos[1] - self.prev[1], c.pos[0] - self.prev[0])
            a2 = math.atan2(nxt[1] - c.pos[1], nxt[0] - c.pos[0])
            turn = min(abs(math.degrees(wrap(a2 - a1))), 90.0)
        return min(self.ap.wp_radius * e2t * e2t, l1) * turn / 90.0

    def loiter_radius(self, radius: float) -> float:
        e2t_sq = self.eas2tas(self.s.z) ** 2
        limit = min(max(self.ap.loiter_bank_limit, 0.0), 89.0)
        if limit <= 0.0:
            return radius * e2t_sq
        sea_level = self.env.airspeed**2 / (G * math.tan(math.radians(limit)))
        if sea_level > radius:
            return radius * e2t_sq
        return max(sea_level * e2t_sq, radius)

    def loiter_done(self, c: NavCommand, laps: float, dz: float) -> bool:
        if c.command == NAV_LOITER_TURNS:
            return laps >= max(float(c.params[0]), 0.0)
        if c.command == NAV_LOITER_TO_ALT:
            return dz <= LOITER_ALTITUDE_M
        return self.s.t - self.loiter_t0 >= c.params[0]

    def exit_heading_ok(self, c: NavCommand, laps: float) -> bool:
        tolerance = EXIT_COURSE_DEG * (1 + int(laps))
        return self.course_lined_up(c, tolerance, EXIT_REACHABLE, abs(self.ap.loiter_radius))

    def exit_point(self, c: NavCommand, radius: float, direction: int) -> tuple | None:
        return self.est

    def loiter_approach_climb(self, c: NavCommand, dist: float, radius: float) -> float | None:
        if self.phase == "track" and dist > 2 * radius:
            assert c.pos is not None
            return self.glide(self.prev, c.pos, radius)
        return None
