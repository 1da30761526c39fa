"""A leg's helix as the items its autopilot flies (the item named by its record's
``helix_command``; mission/builder.py's docstring says why each is so): ArduPlane's
NAV_LOITER_TURNS, the arc's waypoints after it starting beyond its count's slack; PX4's
NAV_LOITER_TO_ALT covering the helix and the arc, left on the heading to the target; or, where
PX4 cannot be told that heading, the helix as waypoints like an arc."""

from __future__ import annotations

import math

import numpy as np

from gcs_planner.aircraft.autopilot import Autopilot
from gcs_planner.geometry.legs import FlownLeg
from gcs_planner.mission.item_writer import ItemWriter
from gcs_planner.mission.items import (
    MAV_CMD_NAV_LOITER_TO_ALT,
    MAV_CMD_NAV_LOITER_TURNS,
)
from gcs_planner.mission.turn_geometry import arc_acceptance, helix_waypoints, px4_leaves_on_heading

# How far past the helix's start ArduPlane's count of its turns may end (degrees): it sums the
# ground course from where it met the circle, which the wind and a late capture move. No arc
# waypoint is written closer than this after an ArduPlane helix (see arc_beyond_the_count).
ARDUPLANE_LAP_SLACK_DEG = 45.0

Helix = tuple[np.ndarray, int, float]  # centre, whole turns, signed radius (turn_geometry)


def counts_turns(ap: Autopilot) -> bool:
    """Whether ``ap`` flies a helix as a loiter that counts its turns (NAV_LOITER_TURNS)."""
    return ap.helix_command == MAV_CMD_NAV_LOITER_TURNS


def arc_beyond_the_count(leg: FlownLeg, arc: np.ndarray) -> np.ndarray:
    """The arc waypoints after a NAV_LOITER_TURNS helix that lie beyond its count's slack.

    ArduPlane ends the turns where its count says (ground course summed from where it met the
    circle) and, the next waypoint on the circle (within 1.05 radii of the centre), leaves at
    once for it: an arc waypoint that lies just past the helix's start may already be behind
    it, and it would fly a whole lap back to it (benchmarks.reserve, dataset 2 in 10 m/s). Arc
    waypoints start beyond the count's slack; with none left it leaves on the course to the
    target."""
    angles = leg.arc_angle * np.arange(1, len(arc) + 1) / len(arc)
    return arc[angles > math.radians(ARDUPLANE_LAP_SLACK_DEG)]


def add_helix(
    w: ItemWriter,
    leg: FlownLeg,
    helix: Helix,
    arc: np.ndarray,
    ap: Autopilot,
    name: str,
    capture: int,
) -> np.ndarray:
    """The items of ``leg``'s ``helix`` (``name``: "FROM->TO"); returns the arc waypoints still
    to be written after them (none when the loiter covers the arc too)."""
    centre, turns, signed = helix
    if counts_turns(ap):
        note = f"helix {name}: {turns} turn(s) to {w.at(centre)['z']:.1f} m"
        w.add(
            MAV_CMD_NAV_LOITER_TURNS,
            w.frame,
            note,
            param1=turns,
            # 1: leave on the tangent exit once the turns are done, as planned
            # (common.xml MAV_CMD_NAV_LOITER_TURNS param2 "heading required"; 0 would
            # let an autopilot leave wherever the turns end; ArduPlane's
            # verify_loiter_turns waits for the heading either way).
            param2=1,
            param3=signed,
            param4=1,
            **w.at(centre),
        )
        return arc
    if px4_leaves_on_heading(leg):
        # Helix and arc as one loiter to the altitude of the arc's end, left on the
        # heading to the target: its tangent point is the arc's end (builder's docstring).
        centre = np.array([centre[0], centre[1], leg.tangent_point[2]])
        note = (
            f"helix and arc {name}: {turns} turn(s) and "
            f"{math.degrees(leg.arc_angle):.0f} deg to {w.at(centre)['z']:.1f} m"
        )
        w.add(
            MAV_CMD_NAV_LOITER_TO_ALT,
            w.frame,
            note,
            param1=1,
            param2=signed,
            param4=1,
            **w.at(centre),
        )
        return arc[:0]
    # A target beside the circle: no exit heading to ask for, so no loiter (it would
    # end wherever the altitude comes in); the helix as waypoints, like an arc.
    pts = helix_waypoints(leg)
    accept = arc_acceptance(leg, capture)
    for j, p in enumerate(pts):
        w.waypoint(f"helix {name} {j + 1}/{len(pts)} ({turns} turn(s))", p, param2=accept)
    return arc
