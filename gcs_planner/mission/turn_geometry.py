"""Where the waypoints of a leg's turns lie: the arc densified so that the autopilot flies the
planned turn, the helix as waypoints or as one loiter (centre, turns, signed radius), and what
each of them asks of the autopilot (the acceptance radius on the circle, whether PX4 can be
told to leave the circle on the heading to the target)."""

from __future__ import annotations

import math

import numpy as np

from gcs_planner.aircraft.profile import MAX_ARC_STEP_DEG, MAX_CHORD_ERROR_M
from gcs_planner.geometry.airplane import AirplaneLeg
from gcs_planner.geometry.legs import FlownLeg

# PX4 enforces a loiter's exit heading (param1) only when the next waypoint is farther than this
# many loiter radii from the centre (mission_block.cpp, exit_heading_is_reachable); the exporter
# asks for it only with this margin more.
PX4_EXIT_HEADING_RANGE = 1.2
PX4_EXIT_MARGIN = 1.05


def arc_step(radius: float) -> float:
    """Largest angle (radians) between arc waypoints: 16 degrees, or less when a 16-degree chord
    would stray more than 2 m from a large arc."""
    step = math.radians(MAX_ARC_STEP_DEG)
    if radius > MAX_CHORD_ERROR_M:
        step = min(step, 2.0 * math.acos(1.0 - MAX_CHORD_ERROR_M / radius))
    return step


def arc_waypoints(leg: FlownLeg) -> np.ndarray:
    """(k, 3) points on the leg's arc after its start (after its helix, if any), evenly spaced in
    angle at most ``arc_step`` apart, the last one the tangent point. Empty for a straight leg."""
    if leg.centre is None or leg.arc_angle <= 0.0 or leg.radius <= 0.0:
        return np.empty((0, 3))
    step = arc_step(leg.radius)
    k = max(1, math.ceil(leg.arc_angle / step - 1e-9))
    angles = leg.arc_angle * np.arange(1, k + 1) / k
    if isinstance(leg, AirplaneLeg):
        turn = leg.run_out + leg.helix_horizontal
        pts = np.array([leg.point_at_horizontal(turn + leg.radius * a) for a in angles])
    else:
        pts = np.array([leg.point_at(leg.radius * a) for a in angles])
    pts[-1] = leg.tangent_point
    return pts


def helix_waypoints(leg: FlownLeg) -> np.ndarray:
    """(k, 3) points on the leg's helix after its start, evenly spaced in angle at most
    ``arc_step`` apart, at the plan's altitudes there; the last one the helix's end, above or
    below the start. Empty when the leg has no helix."""
    if not isinstance(leg, AirplaneLeg) or leg.helix_turns <= 0 or leg.centre is None:
        return np.empty((0, 3))
    total = 2.0 * math.pi * leg.helix_turns
    k = max(1, math.ceil(total / arc_step(leg.radius) - 1e-9))
    pts = leg.points_at_horizontal(leg.run_out + leg.radius * total * np.arange(1, k + 1) / k)
    # whole turns: the helix ends above or below where it started (the run-out's end)
    pts[-1, :2] = leg.point_at_horizontal(leg.run_out)[:2]
    return pts


def helix_loiter(leg: FlownLeg) -> tuple[np.ndarray, int, float] | None:
    """(centre at the altitude reached at the helix's end, whole turns, signed radius: positive
    clockwise) of the leg's helix, None when the leg has none."""
    if not isinstance(leg, AirplaneLeg) or leg.helix_turns <= 0 or leg.centre is None:
        return None
    end_of_helix = leg.point_at_horizontal(leg.run_out + leg.helix_horizontal)
    centre = np.array([leg.centre[0], leg.centre[1], end_of_helix[2]])
    return centre, int(leg.helix_turns), float(-leg.sense * leg.radius)


def px4_leaves_on_heading(leg: FlownLeg) -> bool:
    """Whether PX4 can be told to leave the leg's turning circle on the heading to its target:
    it enforces an exit heading only towards a waypoint farther than 1.2 turning radii from the
    loiter's centre (mission_block.cpp); PX4_EXIT_MARGIN more keeps float rounding out of it."""
    if leg.centre is None or leg.radius <= 0.0:
        return False
    far = math.hypot(leg.end[0] - leg.centre[0], leg.end[1] - leg.centre[1])
    return far > PX4_EXIT_HEADING_RANGE * PX4_EXIT_MARGIN * leg.radius


def last_turn_sense(legs: list[FlownLeg]) -> int:
    """Sense (+1 counter-clockwise, -1 clockwise seen from above) of the route's last turn that
    has one; clockwise when the route never turns."""
    for leg in reversed(legs):
        if leg.sense != 0:
            return leg.sense
    return -1


def arc_acceptance(leg: FlownLeg, capture: int) -> float:
    """param2 of the waypoints on a leg's circle: the autopilot must pass close to them, not cut
    inside the turn, so at most a quarter of the spacing between them."""
    chord = 2.0 * leg.radius * math.sin(arc_step(leg.radius) / 2.0)
    return float(max(1, min(capture, math.floor(chord / 4.0))))
