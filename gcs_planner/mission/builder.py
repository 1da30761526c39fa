"""A planned route (from the plan JSON) as the mission a fixed-wing autopilot flies.

The exporter knows nothing of the search: it reads the plan dict (docs/plan-json.md) and turns
one route of its front into MAVLink mission items (MISSION_ITEM_INT semantics, common.xml):

* ArduPilot (default): seq 0 is home at A, as ArduPilot stores it; PX4 has no home item, so every
  seq is one less (``Mission.point_seqs`` follows).
* A speed item (MAV_CMD_DO_CHANGE_SPEED, airspeed) first, then a NAV_WAYPOINT on A.
* A NAV_WAYPOINT exactly on each correction point, overflown: param2 the acceptance radius (the
  capture radius, a whole number of metres within which the aircraft's correction works), param3
  0 (pass through the point, no orbit offset).
* With a run-out (docs/model.md, "Straight at every landmark"), a NAV_WAYPOINT straight on
  beyond each point, on the heading the aircraft overflew it with (the departure waypoint):
  an autopilot that switches to its next item early (PX4 at its npfg switch distance) then does
  so on this line, past the landmark, and the leg's helix and arc start there.
* Each Dubins arc densified into NAV_WAYPOINTs at most 16 degrees apart and close enough that a
  chord stays within 2 m of the arc (sagitta R(1 - cos(step/2)) <= 2 m), so the autopilot flies
  the planned turn and not its own shortcut. Straight legs need no intermediate item.
* A helix (airplane legs: whole turns on the leg's turning circle to gain or lose height,
  docs/model.md, "Airplane legs")
  becomes a loiter at the circle's centre whose radius is the turning radius, signed by the turn's
  sense (positive = clockwise, MAVLink's convention), with the exit cross-track flag set (param4 =
  1: leave on the tangent towards the next item, not through the centre). The aircraft starts the
  helix on the circle (it enters it from the correction point, tangent to its heading).
  ArduPlane: NAV_LOITER_TURNS at the altitude the plan reaches at the end of the helix, param1 the
  number of turns, counted from when it reaches the circle (verify_loiter_turns sums the heading
  change); the arc's waypoints continue on the same circle after it, from 45 degrees past the
  helix's start on: ArduPlane leaves for a next waypoint on the circle as soon as its count is
  done, and a count that ends late (the wind, a late capture) would find a nearer one behind it
  and fly a lap back to it. With none left it leaves on the course to the target.
  PX4 has no loiter-turns item in missions. Its NAV_LOITER_TO_ALT (param2 the signed radius)
  counts no turns: TECS climbs or sinks at its limit and the loiter ends as soon as the altitude
  is within NAV_FW_ALT_RAD, wherever the aircraft is on the circle (mission_block.cpp), while the
  plan spreads the height over the whole leg; left there, the aircraft cuts across to the next
  item. So PX4's loiter covers the helix AND the arc, to the altitude the plan reaches at the
  arc's end (the tangent point), with param1 = 1 (heading required): it ends only once the course
  points at the target (MIS_YAW_ERR), that is on the last turn as it comes to the tangent point,
  and PX4 starts the next leg from the tangent point it computes from the centre, the plan's own
  (the tangent from the circle to the target). Climbing at its limit the aircraft has the
  altitude only on the last turn (a turn earlier, and the leg would have needed one turn less).
  The target's waypoint follows directly (no arc waypoints). PX4 enforces the heading only
  towards a waypoint farther than 1.2 radii from the centre; for a target closer than that (rare:
  right beside the circle) PX4 gets the helix as waypoints 16 degrees apart, as an arc, then the
  arc's: it overflies the target, but flies each turn some 120 m long (L1 lags on a polygon of
  its own turning radius: it cannot catch up).
* At B a NAV_WAYPOINT on B, then the end action: MAV_CMD_NAV_LOITER_UNLIM about B whose radius is
  the turning radius (positive = clockwise, MAVLink's convention), RTL, or LAND at B at sea level.

Altitudes: MAV_FRAME_GLOBAL (metres above mean sea level) by default, or
MAV_FRAME_GLOBAL_RELATIVE_ALT (metres above home). Relative altitudes need a stated home (where
the aircraft is armed, e.g. a ship's deck): A is the mission's first point, in the air, and the
autopilot takes as home wherever it was armed, so altitudes relative to A would put every item
A's altitude too low (down to -1,283 m in the coast example). Without one the relative frame is
refused. The home (given, or A when none is) is what the files carry as home (.plan's
plannedHomePosition, .waypoints row 0, ArduPilot's seq 0). ArduPlane and PX4 both accept both
frames; any other name is refused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from gcs_planner.aircraft.autopilot import (
    ARDUPLANE,
    DEFAULT_AUTOPILOT,
    PX4,
    Autopilot,
    autopilot_for,
)
from gcs_planner.aircraft.profile import (
    DEFAULT_ACCEPTANCE_RADIUS_M,
    DEFAULT_CRUISE_AIRSPEED,
    FIRMWARES,
)
from gcs_planner.geometry.legs import FlownLeg
from gcs_planner.mission.helix_items import (
    ARDUPLANE_LAP_SLACK_DEG,
    add_helix,
    arc_beyond_the_count,
    counts_turns,
)
from gcs_planner.mission.item_writer import ItemWriter, deg_e7
from gcs_planner.mission.items import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TO_ALT,
    MAV_CMD_NAV_LOITER_TURNS,
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_MISSION,
    MissionItem,
)
from gcs_planner.mission.plan_reading import (
    PLAN_FORMAT,
    PLAN_VERSION,
    check_plan,
    plan_cruise_airspeed,
    plan_design_wind,
    plan_error,
    point_table,
    resolve_origin,
    route_entry,
    route_legs,
    route_xyz,
)
from gcs_planner.mission.run_outs import add_departure, add_run_out_beyond_b, run_out_beyond_b
from gcs_planner.mission.turn_geometry import (
    PX4_EXIT_HEADING_RANGE,
    PX4_EXIT_MARGIN,
    arc_acceptance,
    arc_step,
    arc_waypoints,
    helix_loiter,
    helix_waypoints,
    last_turn_sense,
    px4_leaves_on_heading,
)
from gcs_planner.scenario.georef import LocalFrame, validate_origin
from gcs_planner.scenario.model import Origin

# The names other modules and the tests import from here, where they were first written.
__all__ = [
    "ALTITUDE_FRAMES", "ARDUPLANE_LAP_SLACK_DEG", "DEFAULT_ACCEPTANCE_RADIUS",
    "DEFAULT_CRUISE_SPEED", "END_ACTIONS", "FIRMWARES", "FRAMES_ACCEPTED", "HOVER_SPEED",
    "MAV_CMD_DO_CHANGE_SPEED", "MAV_CMD_NAV_LAND", "MAV_CMD_NAV_LOITER_TO_ALT",
    "MAV_CMD_NAV_LOITER_TURNS", "MAV_CMD_NAV_LOITER_UNLIM", "MAV_CMD_NAV_RETURN_TO_LAUNCH",
    "MAV_CMD_NAV_WAYPOINT", "MAV_FRAME_GLOBAL", "MAV_FRAME_GLOBAL_RELATIVE_ALT",
    "MAV_FRAME_MISSION", "PLAN_FORMAT", "PLAN_VERSION", "PX4_EXIT_HEADING_RANGE",
    "PX4_EXIT_MARGIN", "Mission", "MissionItem", "arc_step", "arc_waypoints", "build_mission",
    "check_plan", "helix_loiter", "helix_waypoints", "last_turn_sense", "plan_cruise_airspeed",
    "plan_design_wind", "point_table", "px4_leaves_on_heading", "resolve_origin", "route_entry",
    "route_legs", "route_xyz",
]  # fmt: skip

# The waypoint acceptance radius (param2 of each correction waypoint): within it the autopilot
# counts the waypoint reached. 50 m is a quarter of the 200 m turning radius: loose enough that a
# fixed wing in wind does not miss the point and circle back.
DEFAULT_ACCEPTANCE_RADIUS = int(DEFAULT_ACCEPTANCE_RADIUS_M)
DEFAULT_CRUISE_SPEED = DEFAULT_CRUISE_AIRSPEED
# QGroundControl's default hover speed; meaningless for a fixed wing but the .plan carries it.
HOVER_SPEED = 5.0

ALTITUDE_FRAMES = {"amsl": MAV_FRAME_GLOBAL, "relative": MAV_FRAME_GLOBAL_RELATIVE_ALT}
# Which altitude frames each autopilot takes in a mission. Both take both; the table is where a
# refusal would be stated.
FRAMES_ACCEPTED = {
    ARDUPLANE.firmware: ("amsl", "relative"),  # AP_Mission
    PX4.firmware: ("amsl", "relative"),  # the mission feasibility checks
}
END_ACTIONS = ("loiter", "rtl", "land")


@dataclass(frozen=True)
class Mission:
    """The mission items of one route and what a ground station needs beside them."""

    items: tuple[MissionItem, ...]
    firmware: str  # "ardupilot" | "px4"
    home: tuple[float, float, float]  # lat, lon (deg), alt (m AMSL) of A
    cruise_speed: float  # m/s
    turn_radius: float  # m; 0 for a straight-leg plan
    # (parameter name, value) the link sets on upload; None when the plan has no turning radius
    # (setting a loiter radius of 0 would break the autopilot's loiters).
    loiter_param: tuple[str, float] | None
    acceptance_radius: float  # m, param2 of every correction waypoint (the autopilot's radius)
    origin: Origin
    origin_is_default: bool
    altitude_frame: str = "amsl"
    at_end: str = "loiter"
    route_index: int = 0
    route: tuple[str, ...] = ()  # point ids, A..B
    # (point id, seq of its NAV_WAYPOINT) for A, every correction point and B, in route order.
    point_seqs: tuple[tuple[str, int], ...] = ()

    @property
    def frame(self) -> int:
        return ALTITUDE_FRAMES[self.altitude_frame]

    def seq_of(self, point_id: str) -> int:
        """Seq of the NAV_WAYPOINT on the route's point ``point_id``."""
        for pid, seq in self.point_seqs:
            if pid == str(point_id):
                return seq
        raise KeyError(point_id)


# ---------------------------------------------------------------------------------------------
# Building the mission


@dataclass(frozen=True)
class _Route:
    """The route being exported, as read from the plan: its index in the front, point ids, flown
    legs, local positions (m), georeference and turning radius."""

    index: int
    ids: list[str]
    legs: list[FlownLeg]
    xyz: np.ndarray
    origin: Origin
    origin_is_default: bool
    params: dict
    radius: float


def _whole_metres(value: Any, name: str) -> int:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise plan_error(f"must be a whole number of metres, got {value!r}", "", name) from exc
    if not math.isfinite(v) or v != round(v) or not 1 <= v <= 10_000:
        raise plan_error(f"must be a whole number of metres in 1..10000, got {value!r}", "", name)
    return int(v)


def _check_options(firmware: str, altitude_frame: str, at_end: str, cruise_speed: Any) -> float:
    if firmware not in FIRMWARES:
        raise plan_error(
            f"unknown firmware {firmware!r} (one of {', '.join(FIRMWARES)})", "", "firmware"
        )
    if altitude_frame not in ALTITUDE_FRAMES:
        raise plan_error(
            f"unknown altitude frame {altitude_frame!r} (one of {', '.join(ALTITUDE_FRAMES)})",
            "",
            "altitude-frame",
        )
    if altitude_frame not in FRAMES_ACCEPTED[firmware]:
        raise plan_error(
            f"{firmware} does not accept the {altitude_frame!r} altitude frame in missions "
            f"(it accepts {', '.join(FRAMES_ACCEPTED[firmware])})",
            "",
            "altitude-frame",
        )
    if at_end not in END_ACTIONS:
        raise plan_error(
            f"unknown end action {at_end!r} (one of {', '.join(END_ACTIONS)})", "", "at-end"
        )
    try:
        speed = float(cruise_speed)
    except (TypeError, ValueError) as exc:
        raise plan_error(
            f"must be a number of m/s, got {cruise_speed!r}", "", "cruise-speed"
        ) from exc
    if not math.isfinite(speed) or not 0.0 < speed <= 1000.0:
        raise plan_error(f"must lie in (0, 1000] m/s, got {cruise_speed!r}", "", "cruise-speed")
    return speed


def _stated_home(home: Origin | None, altitude_frame: str) -> Origin | None:
    """``home`` checked; InputError for the relative frame without one."""
    if home is not None:
        return validate_origin(home, field="--home")
    if altitude_frame == "relative":
        raise plan_error(
            "relative altitudes need a stated home: give --home LAT,LON,ALT (where the "
            "aircraft is armed, ALT in metres above mean sea level); A is in the air, and "
            "altitudes relative to it would be wrong by A's altitude",
            "",
            "--home",
        )
    return None


def _read_route(plan: dict, route_index: int | None, origin: Origin | None, source: str) -> _Route:
    """The route to export (``route_index``, else the chosen one) and its turning radius, read
    and checked in the order a plan's errors are reported."""
    k, entry = route_entry(plan, route_index, source)
    legs = route_legs(entry, source)
    ids = [str(p) for p in entry["route"]]
    xyz = route_xyz(plan, entry, legs, source)
    org, org_default = resolve_origin(plan, origin, source)
    params = plan.get("parameters") if isinstance(plan.get("parameters"), dict) else {}
    try:
        radius = float(params.get("turn_radius", legs[0].radius))
    except (TypeError, ValueError) as exc:
        raise plan_error("parameters.turn_radius must be a number", source, "turn_radius") from exc
    if not math.isfinite(radius) or radius < 0:
        raise plan_error(
            f"parameters.turn_radius must be >= 0, got {radius!r}", source, "turn_radius"
        )
    return _Route(k, ids, legs, xyz, org, org_default, params, radius)


def build_mission(
    plan: dict,
    *,
    route_index: int | None = None,
    firmware: str = DEFAULT_AUTOPILOT,
    altitude_frame: str = "amsl",
    acceptance_radius: float = DEFAULT_ACCEPTANCE_RADIUS,
    cruise_speed: float | None = None,
    at_end: str = "loiter",
    origin: Origin | None = None,
    home: Origin | None = None,
    source: str = "",
) -> Mission:
    """The mission for route ``route_index`` of ``plan`` (default: the plan's chosen route).

    ``origin`` overrides the scenario's; without either the default origin is used and
    ``Mission.origin_is_default`` is True (the caller warns). ``home`` (lat, lon, alt AMSL) is
    where the aircraft is armed: the files' home, and what relative altitudes are measured from
    (``altitude_frame="relative"`` is refused without it). ``source`` names the plan file in
    error messages. ``cruise_speed`` (m/s, the DO_CHANGE_SPEED airspeed) defaults to the plan's
    own cruise airspeed: its climb angles and turning radius were derived for it, and the same
    climb rate at a faster airspeed is a flatter climb (a plan for 12 m/s flown at 25 m/s misses
    its climbing landmarks by up to 180 m).
    """
    if cruise_speed is None:
        cruise_speed = plan_cruise_airspeed(plan, source)
    speed = _check_options(firmware, altitude_frame, at_end, cruise_speed)
    home = _stated_home(home, altitude_frame)
    capture = _whole_metres(acceptance_radius, "acceptance-radius")
    route = _read_route(plan, route_index, origin, source)
    ap = autopilot_for(firmware)
    local = LocalFrame(route.origin)
    if home is None:
        home_lat, home_lon, home_alt = local.to_geodetic(*route.xyz[0])
    else:
        home_lat, home_lon, home_alt = home.lat, home.lon, home.alt
    alt_offset = home_alt if altitude_frame == "relative" else 0.0
    w = ItemWriter(local, ALTITUDE_FRAMES[altitude_frame], alt_offset)

    if ap.home_at_seq0:
        home_at = {"x": deg_e7(home_lat), "y": deg_e7(home_lon), "z": float(home_alt)}
        w.add(MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL, "home (A)", **home_at)
    # Airspeed (param1 0), no throttle change (param3 -1).
    w.add(
        MAV_CMD_DO_CHANGE_SPEED,
        MAV_FRAME_MISSION,
        "cruise speed",
        param1=0,
        param2=speed,
        param3=-1,
    )
    ids = route.ids
    point_seqs = [(ids[0], w.waypoint(f"A {ids[0]}", route.xyz[0]))]
    for i, leg in enumerate(route.legs):
        point_seqs.append((ids[i + 1], _add_leg(w, ap, route, i, leg, capture)))
    _add_end(w, ap, plan, route, at_end, capture, speed, source)

    return Mission(
        items=tuple(w.items),
        firmware=firmware,
        home=(float(home_lat), float(home_lon), float(home_alt)),
        cruise_speed=speed,
        turn_radius=route.radius,
        loiter_param=(ap.loiter_radius_param, route.radius) if route.radius > 0 else None,
        acceptance_radius=float(capture),
        origin=route.origin,
        origin_is_default=route.origin_is_default,
        altitude_frame=altitude_frame,
        at_end=at_end,
        route_index=route.index,
        route=tuple(ids),
        point_seqs=tuple(point_seqs),
    )


def _add_leg(
    w: ItemWriter, ap: Autopilot, route: _Route, i: int, leg: FlownLeg, capture: int
) -> int:
    """The items of leg ``i`` (its departure, helix and arc, then the waypoint on its target);
    the seq of the target's waypoint."""
    ids, target = route.ids, route.xyz[i + 1]
    add_departure(w, leg, route.xyz[i], ids[i], ap, capture)
    helix = helix_loiter(leg)
    arc = arc_waypoints(leg)
    if helix is not None and counts_turns(ap) and len(arc):
        arc = arc_beyond_the_count(leg, arc)
    # A tangent point on the target itself (no straight part) is the target's own waypoint.
    if len(arc) and np.linalg.norm(arc[-1] - target) < 1.0:
        arc = arc[:-1]
    if helix is not None:
        arc = add_helix(w, leg, helix, arc, ap, f"{ids[i]}->{ids[i + 1]}", capture)
    arc_accept = arc_acceptance(leg, capture)
    for j, p in enumerate(arc):
        w.waypoint(f"arc {ids[i]}->{ids[i + 1]} {j + 1}/{len(arc)}", p, param2=arc_accept)
    label = "B" if i == len(route.legs) - 1 else "correction"
    return w.waypoint(f"{label} {ids[i + 1]}", target, param2=capture, param3=0)


def _add_end(
    w: ItemWriter,
    ap: Autopilot,
    plan: dict,
    route: _Route,
    at_end: str,
    capture: int,
    speed: float,
    source: str,
) -> None:
    """The run-out beyond B, where there is one, then the end action at B."""
    b_xyz = route.xyz[-1]
    beyond = run_out_beyond_b(
        plan, route.params, route.legs[-1], route.radius, speed, route.origin.alt, ap, source
    )
    if beyond is not None:
        add_run_out_beyond_b(w, beyond, b_xyz, route.ids[-1], capture)
    b = w.at(b_xyz)
    if at_end == "loiter":
        # MAVLink: a positive loiter radius is clockwise; 0 leaves the autopilot's own radius.
        radius = route.radius
        signed = float(-last_turn_sense(route.legs) * radius) if radius > 0 else 0.0
        w.add(MAV_CMD_NAV_LOITER_UNLIM, w.frame, "end: loiter at B", param3=signed, **b)
    elif at_end == "rtl":
        w.add(MAV_CMD_NAV_RETURN_TO_LAUNCH, MAV_FRAME_MISSION, "end: return to launch")
    else:
        # Maritime: the surface at B is sea level, 0 m AMSL.
        z = 0.0 - w.alt_offset
        w.add(MAV_CMD_NAV_LAND, w.frame, "end: land at B", x=b["x"], y=b["y"], z=z)
