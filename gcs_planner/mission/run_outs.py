"""The straight run-outs of a mission (docs/model.md, "Straight at every landmark"): the departure
waypoint straight on beyond a landmark, on the heading the aircraft overflew it with, and the
run-out beyond B before the end action. An autopilot that switches to its next item early
(PX4 at npfg's switch distance) then does so on this line, past the landmark."""

from __future__ import annotations

import math

import numpy as np

from gcs_planner.aircraft.autopilot import Autopilot, effective
from gcs_planner.aircraft.profile import tas_from_eas
from gcs_planner.geometry.airplane import AirplaneLeg
from gcs_planner.geometry.legs import FlownLeg
from gcs_planner.mission.item_writer import ItemWriter
from gcs_planner.mission.plan_reading import plan_design_wind, plan_error


def add_departure(
    w: ItemWriter, leg: FlownLeg, landmark: np.ndarray, name: str, ap: Autopilot, capture: int
) -> None:
    """The departure waypoint of ``leg`` (none when the leg has no run-out): straight on over
    the landmark ``name`` at ``landmark`` before the next turn."""
    departure = getattr(leg, "departure_point", None)
    if departure is None:
        return
    note = f"departure {name} ({leg.run_out:.0f} m straight on)"
    if ap.climbs_at_once:
        # PX4 climbs at once towards its current item's altitude and switches to it npfg's
        # switch distance before the landmark: a run-out on the leg's slope would have it
        # climbing away before it overflies the landmark (missed by rate x switch time).
        # Level at the landmark's altitude, it crosses it there; the setup's rates cover
        # the leg's climb over what is left (mission/vehicle_setup.py).
        departure = np.array([departure[0], departure[1], landmark[2]])
    w.waypoint(note, departure, param2=capture)


def run_out_beyond_b(
    plan: dict,
    params: dict,
    last: FlownLeg,
    radius: float,
    eas: float,
    base_alt: float,
    ap: Autopilot,
    source: str = "",
) -> np.ndarray | None:
    """Where the run-out beyond B ends: the plan's (``parameters.departure``), else, for an
    autopilot that switches early, its settle distance; None when there is none."""
    beyond = _departure_beyond_b(params, last, radius, source)
    if beyond is None and ap.switches_early:
        beyond = _settle_run_out_beyond_b(plan, last, radius, eas, base_alt, ap, source)
    return beyond


def add_run_out_beyond_b(
    w: ItemWriter, beyond: np.ndarray, b: np.ndarray, name: str, capture: int
) -> None:
    """B overflown straight on too: an autopilot that switches to the end action early (PX4
    turns into its loiter at its switch distance) would pass B outside its capture radius."""
    note = f"departure {name} ({float(np.linalg.norm(beyond[:2] - b[:2])):.0f} m on)"
    w.waypoint(note, beyond, param2=capture)


def _departure_beyond_b(
    params: dict, last: FlownLeg, radius: float, source: str
) -> np.ndarray | None:
    """Where the run-out beyond B ends (B's altitude, along the heading the last leg arrives
    with), or None when the plan has no run-out (``parameters.departure``, 0 in earlier plan
    files) or straight legs."""
    try:
        departure = float(params.get("departure", 0.0))
    except (TypeError, ValueError) as exc:
        raise plan_error("parameters.departure must be a number", source, "departure") from exc
    if not math.isfinite(departure) or departure < 0:
        raise plan_error(
            f"parameters.departure must be >= 0, got {departure!r}", source, "departure"
        )
    if departure <= 0 or radius <= 0 or not isinstance(last, AirplaneLeg):
        return None
    return _straight_on_beyond_b(last, departure)


def _straight_on_beyond_b(last: FlownLeg, run_out: float) -> np.ndarray:
    """The point ``run_out`` metres beyond B on the heading the last leg arrives with, at B's
    altitude."""
    out = np.asarray(last.heading_out, dtype=float)
    return np.array([*(last.end[:2] + run_out * out[:2]), last.end[2]])


def _settle_run_out_beyond_b(
    plan: dict,
    last: FlownLeg,
    radius: float,
    eas: float,
    base_alt: float,
    ap: Autopilot,
    source: str = "",
) -> np.ndarray | None:
    """Where a run-out beyond B ends for an autopilot that switches early when the plan has
    none: PX4 switches to its next item npfg's switch distance early
    (Navigator::get_acceptance_radius), so with the end action next it turns away before B and
    passes it outside the capture radius (the bundled missions/jsbsim in still air: 7.9 m off).
    Nothing is planned after B, so the run-out costs the plan nothing: the path follower's settle
    distance (npfg's track error bound, as a derived plan's run-out at every landmark) at the
    ground speed, B's TAS for ``eas`` plus the plan's design wind. None for straight legs."""
    if radius <= 0 or not isinstance(last, AirplaneLeg):
        return None
    ground_speed = tas_from_eas(eas, float(last.end[2]) + base_alt) + plan_design_wind(plan, source)
    return _straight_on_beyond_b(last, effective(ap.firmware, {}).settle_distance(ground_speed))
