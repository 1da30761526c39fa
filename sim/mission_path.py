"""The stored mission's path as the vehicle reads it (straight chords from item to item, the
nominal path a flight is compared with) and the flown track as a path, in the scenario's local
frame.

A chord under an arc of angle a is shorter than the arc by the factor sin(a/2)/(a/2), at most
``CHORD_SHORTFALL`` for the exporter's ``DENSIFY_MAX_DEG`` steps, plus ``QUANTISATION_M`` per
waypoint for the degE7 quantisation of latitude/longitude: the tolerance the dry run holds the
nominal path's length to.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from gcs_planner.sim import guidance
from gcs_planner.sim.replay_records import FlightPath

from gcs_planner.aircraft.profile import DEFAULT_CAPTURE_RADIUS_M, DEFAULT_CRUISE_AIRSPEED
from gcs_planner.mission.items import (
    GLOBAL_AMSL_FRAMES,
    GLOBAL_RELATIVE_FRAMES,
    POSITION_COMMANDS,
    MissionItem,
)
from gcs_planner.scenario.georef import DEFAULT_ORIGIN, LocalFrame
from gcs_planner.scenario.model import Scenario

MAV_CMD_DO_CHANGE_SPEED = 178

DEFAULT_CRUISE_SPEED = DEFAULT_CRUISE_AIRSPEED  # m/s
DENSIFY_MAX_DEG = 16.0
# Largest relative shortfall of a chord under an arc of DENSIFY_MAX_DEG (see module docstring).
CHORD_SHORTFALL = 1.0 - math.sin(math.radians(DENSIFY_MAX_DEG) / 2) / (
    math.radians(DENSIFY_MAX_DEG) / 2
)
QUANTISATION_M = 0.02  # per waypoint: 1e-7 degree is at most 1.1 cm on each axis


def scenario_frame(scenario: Scenario) -> LocalFrame:
    """The vehicle's local frame: the scenario's origin, or the project's default one."""
    return LocalFrame(scenario.origin or DEFAULT_ORIGIN)


def decode_path(
    items: Sequence[MissionItem],
    scenario: Scenario,
    *,
    home_at_seq0: bool = False,
    home_alt: float | None = None,
    cruise_speed: float = DEFAULT_CRUISE_SPEED,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    frame: LocalFrame | None = None,
) -> FlightPath:
    """The path of the stored mission in the scenario's local frame, starting at A.

    ``home_at_seq0``: item 0 is the home position (ArduPilot), not a place to fly to.
    Altitudes of relative frames are above ``home_alt``, by default the altitude of home, which
    is where the vehicle stands: A.

    The flight ends at the first waypoint within ``capture_radius`` of B: what the mission does
    after B (loiter, land, return) is not part of the route and is not flown.
    """
    frame = frame or scenario_frame(scenario)
    a = np.asarray(scenario.xyz[scenario.start], float)
    base_alt = float(a[2] + frame.origin.alt) if home_alt is None else home_alt
    points = [a]
    seqs = [-1]
    speeds = [0.0]
    speed = cruise_speed
    for item in items:
        if home_at_seq0 and item.seq == 0:
            continue
        if item.command == MAV_CMD_DO_CHANGE_SPEED and item.param2 > 0:
            speed = float(item.param2)
            continue
        if item.command not in POSITION_COMMANDS:
            continue
        if item.frame in GLOBAL_AMSL_FRAMES:
            alt = item.z
        elif item.frame in GLOBAL_RELATIVE_FRAMES:
            alt = item.z + base_alt
        else:
            continue  # no position the replay can place (the vehicle refuses such frames)
        # MissionItem holds degE7 whatever the frame's spelling (items.py).
        x, y, z = frame.to_local(item.x / 1e7, item.y / 1e7, alt)
        points.append(np.array([x, y, z]))
        seqs.append(item.seq)
        speeds.append(speed)
        if np.linalg.norm(points[-1] - scenario.xyz[scenario.end]) <= capture_radius:
            break
    return FlightPath(np.vstack(points), tuple(seqs), tuple(speeds))


def flown_path(flight: guidance.Flight) -> FlightPath:
    """The flown track as a path (one point per step of the flight model)."""
    # Contiguous: the compiled closest approaches read it many times.
    points = np.ascontiguousarray(flight.xyz, dtype=float)
    return FlightPath(points, tuple(flight.current.tolist()), tuple(flight.airspeed.tolist()))
