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

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.aircraft.profile import (
    DEFAULT_ACCEPTANCE_RADIUS_M,
    DEFAULT_CRUISE_AIRSPEED,
    FIRMWARES,
    LOITER_RADIUS_PARAM,
    MAX_ARC_STEP_DEG,
    MAX_CHORD_ERROR_M,
)
from gcs_planner.errors import InputError
from gcs_planner.geometry.airplane import AirplaneLeg
from gcs_planner.geometry.legs import FlownLeg
from gcs_planner.geometry.trajectory import leg_from_dict
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
from gcs_planner.scenario.georef import DEFAULT_ORIGIN, LocalFrame, validate_origin
from gcs_planner.scenario.model import Origin

# The waypoint acceptance radius (param2 of each correction waypoint): within it the autopilot
# counts the waypoint reached. 50 m is a quarter of the 200 m turning radius: loose enough that a
# fixed wing in wind does not miss the point and circle back.
DEFAULT_ACCEPTANCE_RADIUS = int(DEFAULT_ACCEPTANCE_RADIUS_M)
DEFAULT_CRUISE_SPEED = DEFAULT_CRUISE_AIRSPEED
# QGroundControl's default hover speed; meaningless for a fixed wing but the .plan carries it.
HOVER_SPEED = 5.0

ALTITUDE_FRAMES = {"amsl": MAV_FRAME_GLOBAL, "relative": MAV_FRAME_GLOBAL_RELATIVE_ALT}
# Which altitude frames each firmware takes in a mission (ArduPlane: AP_Mission; PX4: the
# mission feasibility checks). Both take both; the table is where a refusal would be stated.
FRAMES_ACCEPTED = {"ardupilot": ("amsl", "relative"), "px4": ("amsl", "relative")}
END_ACTIONS = ("loiter", "rtl", "land")

# PX4 enforces a loiter's exit heading (param1) only when the next waypoint is farther than this
# many loiter radii from the centre (mission_block.cpp, exit_heading_is_reachable); the exporter
# asks for it only with this margin more.
PX4_EXIT_HEADING_RANGE = 1.2
PX4_EXIT_MARGIN = 1.05
# How far past the helix's start ArduPlane's count of its turns may end (degrees): it sums the
# ground course from where it met the circle, which the wind and a late capture move. No arc
# waypoint is written closer than this after an ArduPlane helix (see build_mission).
ARDUPLANE_LAP_SLACK_DEG = 45.0

PLAN_FORMAT = "gcs-planner-plan"
PLAN_VERSION = 1


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
# Reading the plan dict


def _bad(message: str, source: str, field: str | None = None) -> InputError:
    return InputError(message, file=source, field=field)


def check_plan(plan: Any, source: str = "") -> None:
    """Raise InputError unless ``plan`` looks like a plan JSON this module can read."""
    if not isinstance(plan, dict):
        raise _bad("not a plan: expected a JSON object", source)
    if plan.get("format") != PLAN_FORMAT:
        raise _bad(f"not a plan: 'format' must be {PLAN_FORMAT!r}", source, "format")
    if plan.get("version") != PLAN_VERSION:
        raise _bad(
            f"unsupported plan version {plan.get('version')!r} (this reader knows {PLAN_VERSION})",
            source,
            "version",
        )
    front = plan.get("front")
    if not isinstance(front, list) or not front:
        raise _bad("the plan has no route: 'front' must be a non-empty list", source, "front")
    chosen = plan.get("chosen")
    if isinstance(chosen, bool) or not isinstance(chosen, int) or not 0 <= chosen < len(front):
        raise _bad(
            f"'chosen' must be an index into 'front' (0..{len(front) - 1}), got {chosen!r}",
            source,
            "chosen",
        )
    scenario = plan.get("scenario")
    if not isinstance(scenario, dict):
        raise _bad("'scenario' must be an object (docs/plan-json.md)", source, "scenario")
    # A plan that lost its origin must not be exported to the default one: that puts the
    # mission tens of kilometres from its landmarks. `null` is how a plan says it has none.
    if "origin" not in scenario:
        raise _bad(
            "the plan has lost its georeference: 'scenario.origin' must be there, an object "
            "{lat, lon, alt} or null (re-run `gcs-planner plan` to write it again)",
            source,
            "scenario.origin",
        )
    is_default = scenario.get("origin_is_default", False)
    if not isinstance(is_default, bool):
        raise _bad(
            f"'scenario.origin_is_default' must be true or false, got {is_default!r}",
            source,
            "scenario.origin_is_default",
        )
    resolve_origin(plan, None, source)  # an origin of numbers in range, not contradicted
    params = plan.get("parameters")
    if not isinstance(params, dict):
        raise _bad("'parameters' must be an object (docs/plan-json.md)", source, "parameters")
    if "turn_radius" not in params:
        raise _bad("'parameters.turn_radius' is missing", source, "parameters.turn_radius")
    radius = params["turn_radius"]
    if not _is_number(radius) or not radius >= 0:
        raise _bad(
            f"'parameters.turn_radius' must be a finite number of metres >= 0 (0: straight "
            f"legs), got {radius!r}",
            source,
            "parameters.turn_radius",
        )
    points = plan.get("points")
    if points is not None and not isinstance(points, list):
        raise _bad("'points' must be a list of points", source, "points")
    ids = None if points is None else {str(q.get("id")) for q in points if isinstance(q, dict)}
    for k, entry in enumerate(front):
        _check_entry(entry, k, ids, source)


def _check_entry(entry: Any, k: int, ids: set[str] | None, source: str) -> None:
    """One route of the front: its points and one leg per point after A, each point in the
    plan's points table (a route through a point the plan does not have contradicts it)."""
    if not isinstance(entry, dict):
        raise _bad(f"front[{k}] is not an object", source, "front")
    route, legs = entry.get("route"), entry.get("legs")
    if not isinstance(route, list) or len(route) < 2:
        raise _bad(f"front[{k}].route must list at least A and B", source, f"front[{k}].route")
    if not isinstance(legs, list) or len(legs) != len(route) - 1:
        raise _bad(
            f"front[{k}].legs must have one leg per point after A", source, f"front[{k}].legs"
        )
    if ids is not None:
        missing = [str(pid) for pid in route if str(pid) not in ids]
        if missing:
            raise _bad(
                f"front[{k}].route goes through point {missing[0]!r}, which 'points' does not have",
                source,
                f"front[{k}].route",
            )
    _check_figures(entry, f"front[{k}]", source, required=("length",))
    corrections = entry.get("corrections", 0)
    if isinstance(corrections, bool) or not isinstance(corrections, int) or corrections < 0:
        raise _bad(
            f"front[{k}].corrections must be a whole number >= 0, got {corrections!r}",
            source,
            f"front[{k}].corrections",
        )
    for i, leg in enumerate(legs):
        if isinstance(leg, dict):
            _check_figures(leg, f"front[{k}].legs[{i}]", source)


# The figures of a route and of its legs that readers print, plot and write to files: each a
# finite number (probabilities in [0, 1]). Lengths are metres flown, never negative.
_FIGURES = (
    "length", "probability", "gap", "lower_bound", "arc", "straight", "turn_angle_deg",
    "path_angle_deg", "cumulative", "v_error", "h_error", "v_limit", "h_limit", "v_margin",
    "h_margin", "p_arrive",
)  # fmt: skip
_NOT_NEGATIVE = ("length", "gap", "lower_bound", "arc", "straight", "cumulative")
_PROBABILITIES = ("probability", "p_arrive")


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _check_figures(entry: dict, where: str, source: str, required: tuple[str, ...] = ()) -> None:
    """InputError naming ``where.<field>`` for a figure that is not a finite number in range
    (NaN, null, text, a probability of 1.7, a negative length); those in ``required`` must be
    there."""
    for name in _FIGURES:
        if name not in entry and name not in required:
            continue
        value = entry.get(name)
        if name in _PROBABILITIES:
            ok, want = _is_number(value) and 0.0 <= value <= 1.0, "a probability in [0, 1]"
        elif name in _NOT_NEGATIVE:
            ok, want = _is_number(value) and value >= 0.0, "a finite number >= 0"
        else:
            ok, want = _is_number(value), "a finite number"
        if not ok:
            got = "nothing" if name not in entry else repr(value)
            raise _bad(f"{where}.{name} must be {want}, got {got}", source, f"{where}.{name}")


def route_entry(plan: dict, route_index: int | None = None, source: str = "") -> tuple[int, dict]:
    """(index, entry) of the route to export: ``route_index`` or the plan's chosen one."""
    check_plan(plan, source)
    front = plan["front"]
    k = plan.get("chosen", 0) if route_index is None else route_index
    if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(front):
        field = "chosen" if route_index is None else "--route-index"
        raise _bad(f"route index {k!r} is not in the front (0..{len(front) - 1})", source, field)
    entry = front[k]
    if not isinstance(entry, dict):
        raise _bad(f"front[{k}] is not an object", source, "front")
    route, legs = entry.get("route"), entry.get("legs")
    if not isinstance(route, list) or len(route) < 2:
        raise _bad(f"front[{k}].route must list at least A and B", source, "route")
    if not isinstance(legs, list) or len(legs) != len(route) - 1:
        raise _bad(f"front[{k}].legs must have one leg per point after A", source, "legs")
    return k, entry


def route_legs(entry: dict, source: str = "") -> list[FlownLeg]:
    """The flown legs of a front entry, from their ``geometry``."""
    out = []
    for i, leg in enumerate(entry["legs"]):
        try:
            out.append(leg_from_dict(leg.get("geometry") if isinstance(leg, dict) else None))
        except ValueError as exc:
            raise _bad(f"legs[{i}].geometry: {exc}", source, "geometry") from exc
    return out


def point_table(plan: dict) -> dict[str, dict]:
    """The plan's ``points`` by id (empty when the plan does not carry them)."""
    points = plan.get("points")
    if not isinstance(points, list):
        return {}
    return {str(p["id"]): p for p in points if isinstance(p, dict) and "id" in p}


def route_xyz(plan: dict, entry: dict, legs: list[FlownLeg], source: str = "") -> np.ndarray:
    """(m, 3) local positions of the route's points: the points table where it has them (the
    scenario's own coordinates), else the ends of the legs."""
    table = point_table(plan)
    xyz = [legs[0].start] + [leg.end for leg in legs]
    out = np.empty((len(xyz), 3))
    for i, (pid, fallback) in enumerate(zip(entry["route"], xyz, strict=True)):
        p = table.get(str(pid))
        try:
            out[i] = [float(p["x"]), float(p["y"]), float(p["z"])] if p else fallback
        except (KeyError, TypeError, ValueError) as exc:
            raise _bad(f"point {pid!r} needs numbers x, y, z", source, "points") from exc
    if not np.all(np.isfinite(out)):
        raise _bad("route points must have finite coordinates", source, "points")
    return out


def resolve_origin(plan: dict, origin: Origin | None, source: str = "") -> tuple[Origin, bool]:
    """(origin, is_default): the given one, else the plan's scenario origin, else the default."""
    if origin is not None:
        return validate_origin(origin, file=source, field="--origin"), False
    scen = plan.get("scenario") if isinstance(plan.get("scenario"), dict) else {}
    o = scen.get("origin")
    field = "scenario.origin"
    if isinstance(o, dict):
        try:
            lat, lon = o["lat"], o["lon"]
            alt = o.get("alt", 0.0)
            if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in (lat, lon, alt)):
                raise TypeError
            given = Origin(float(lat), float(lon), float(alt))
        except (KeyError, TypeError) as exc:
            raise _bad(
                f"scenario.origin must have numbers lat, lon[, alt]: {o!r}", source, field
            ) from exc
        given = validate_origin(given, file=source, field=field)
        is_default = bool(scen.get("origin_is_default", False))
        if is_default and given != DEFAULT_ORIGIN:
            raise _bad(
                f"scenario.origin {given.lat}, {given.lon} contradicts "
                "'origin_is_default': true (the default origin is "
                f"{DEFAULT_ORIGIN.lat}, {DEFAULT_ORIGIN.lon})",
                source,
                "scenario.origin_is_default",
            )
        return given, is_default
    if o is not None:
        raise _bad(f"scenario.origin must be an object or null, got {o!r}", source, field)
    return DEFAULT_ORIGIN, True


# ---------------------------------------------------------------------------------------------
# Geometry of the arcs


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


# ---------------------------------------------------------------------------------------------
# Building the mission


def _whole_metres(value: Any, name: str) -> int:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise _bad(f"must be a whole number of metres, got {value!r}", "", name) from exc
    if not math.isfinite(v) or v != round(v) or not 1 <= v <= 10_000:
        raise _bad(f"must be a whole number of metres in 1..10000, got {value!r}", "", name)
    return int(v)


def plan_cruise_airspeed(plan: dict, source: str = "") -> float:
    """The cruise airspeed (m/s EAS) the plan's envelope was made for: ``vehicle.cruise_airspeed``
    (the default airspeed in plan files of releases that did not write it)."""
    vehicle = plan.get("vehicle")
    if not isinstance(vehicle, dict) or "cruise_airspeed" not in vehicle:
        return DEFAULT_CRUISE_SPEED
    try:
        speed = float(vehicle["cruise_airspeed"])
    except (TypeError, ValueError) as exc:
        raise _bad(
            f"vehicle.cruise_airspeed must be a number, got {vehicle['cruise_airspeed']!r}",
            source,
            "vehicle.cruise_airspeed",
        ) from exc
    if not math.isfinite(speed) or not 0.0 < speed <= 1000.0:
        raise _bad(
            f"vehicle.cruise_airspeed must lie in (0, 1000] m/s, got {speed!r}",
            source,
            "vehicle.cruise_airspeed",
        )
    return speed


def plan_design_wind(plan: dict, source: str = "") -> float:
    """The design wind (m/s) the plan's envelope was derived for: ``vehicle.envelope.
    design_wind``; 0 when the envelope was stated (no ``envelope``) or the file predates it."""
    vehicle = plan.get("vehicle")
    envelope = vehicle.get("envelope") if isinstance(vehicle, dict) else None
    if not isinstance(envelope, dict) or "design_wind" not in envelope:
        return 0.0
    try:
        wind = float(envelope["design_wind"])
    except (TypeError, ValueError) as exc:
        raise _bad(
            "vehicle.envelope.design_wind must be a number",
            source,
            "vehicle.envelope.design_wind",
        ) from exc
    if not math.isfinite(wind) or wind < 0:
        raise _bad(
            f"vehicle.envelope.design_wind must be >= 0 m/s, got {wind!r}",
            source,
            "vehicle.envelope.design_wind",
        )
    return wind


def _check_options(firmware: str, altitude_frame: str, at_end: str, cruise_speed: Any) -> float:
    if firmware not in FIRMWARES:
        raise _bad(f"unknown firmware {firmware!r} (one of {', '.join(FIRMWARES)})", "", "firmware")
    if altitude_frame not in ALTITUDE_FRAMES:
        raise _bad(
            f"unknown altitude frame {altitude_frame!r} (one of {', '.join(ALTITUDE_FRAMES)})",
            "",
            "altitude-frame",
        )
    if altitude_frame not in FRAMES_ACCEPTED[firmware]:
        raise _bad(
            f"{firmware} does not accept the {altitude_frame!r} altitude frame in missions "
            f"(it accepts {', '.join(FRAMES_ACCEPTED[firmware])})",
            "",
            "altitude-frame",
        )
    if at_end not in END_ACTIONS:
        raise _bad(f"unknown end action {at_end!r} (one of {', '.join(END_ACTIONS)})", "", "at-end")
    try:
        speed = float(cruise_speed)
    except (TypeError, ValueError) as exc:
        raise _bad(f"must be a number of m/s, got {cruise_speed!r}", "", "cruise-speed") from exc
    if not math.isfinite(speed) or not 0.0 < speed <= 1000.0:
        raise _bad(f"must lie in (0, 1000] m/s, got {cruise_speed!r}", "", "cruise-speed")
    return speed


def build_mission(
    plan: dict,
    *,
    route_index: int | None = None,
    firmware: str = "ardupilot",
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
    if home is not None:
        home = validate_origin(home, field="--home")
    elif altitude_frame == "relative":
        raise _bad(
            "relative altitudes need a stated home: give --home LAT,LON,ALT (where the "
            "aircraft is armed, ALT in metres above mean sea level); A is in the air, and "
            "altitudes relative to it would be wrong by A's altitude",
            "",
            "--home",
        )
    capture = _whole_metres(acceptance_radius, "acceptance-radius")
    k, entry = route_entry(plan, route_index, source)
    legs = route_legs(entry, source)
    ids = [str(p) for p in entry["route"]]
    xyz = route_xyz(plan, entry, legs, source)
    org, org_default = resolve_origin(plan, origin, source)
    frame = LocalFrame(org)
    params = plan.get("parameters") if isinstance(plan.get("parameters"), dict) else {}
    try:
        radius = float(params.get("turn_radius", legs[0].radius))
    except (TypeError, ValueError) as exc:
        raise _bad("parameters.turn_radius must be a number", source, "turn_radius") from exc
    if not math.isfinite(radius) or radius < 0:
        raise _bad(f"parameters.turn_radius must be >= 0, got {radius!r}", source, "turn_radius")

    if home is None:
        home_lat, home_lon, home_alt = frame.to_geodetic(*xyz[0])
    else:
        home_lat, home_lon, home_alt = home.lat, home.lon, home.alt
    mav_frame = ALTITUDE_FRAMES[altitude_frame]
    alt_offset = home_alt if altitude_frame == "relative" else 0.0

    items: list[MissionItem] = []
    point_seqs: list[tuple[str, int]] = []

    def add(command: int, frame_: int, note: str, **fields: Any) -> int:
        for name in ("param1", "param2", "param3", "param4", "z"):
            if name in fields:
                fields[name] = float(fields[name])
        items.append(
            MissionItem(seq=len(items), frame=frame_, command=command, note=note, **fields)
        )
        return items[-1].seq

    def at(p: np.ndarray) -> dict[str, Any]:
        lat, lon, alt = frame.to_geodetic(*p)
        return {"x": _deg_e7(lat), "y": _deg_e7(lon), "z": float(alt) - alt_offset}

    if keeps_home_item(firmware):
        home_at = {"x": _deg_e7(home_lat), "y": _deg_e7(home_lon), "z": float(home_alt)}
        add(MAV_CMD_NAV_WAYPOINT, MAV_FRAME_GLOBAL, "home (A)", **home_at)
    # Airspeed (param1 0), no throttle change (param3 -1).
    add(
        MAV_CMD_DO_CHANGE_SPEED,
        MAV_FRAME_MISSION,
        "cruise speed",
        param1=0,
        param2=speed,
        param3=-1,
    )
    point_seqs.append((ids[0], add(MAV_CMD_NAV_WAYPOINT, mav_frame, f"A {ids[0]}", **at(xyz[0]))))

    n_legs = len(legs)
    for i, leg in enumerate(legs):
        departure = getattr(leg, "departure_point", None)
        if departure is not None:
            # Straight on over the landmark before the next turn (docs/model.md, "Straight at
            # every landmark"): an autopilot that switches to the next item early does so on
            # this line, beyond the landmark.
            note = f"departure {ids[i]} ({leg.run_out:.0f} m straight on)"
            if firmware == "px4":
                # PX4 climbs at once towards its current item's altitude and switches to it npfg's
                # switch distance before the landmark: a run-out on the leg's slope would have it
                # climbing away before it overflies the landmark (missed by rate x switch time).
                # Level at the landmark's altitude, it crosses it there; the setup's rates cover
                # the leg's climb over what is left (mission/vehicle_setup.py).
                departure = np.array([departure[0], departure[1], xyz[i][2]])
            add(MAV_CMD_NAV_WAYPOINT, mav_frame, note, param2=capture, **at(departure))
        helix = helix_loiter(leg)
        arc = arc_waypoints(leg)
        if helix is not None and firmware == "ardupilot" and len(arc):
            # ArduPlane ends the turns where its count says (ground course summed from where
            # it met the circle) and, the next waypoint on the circle (within 1.05 radii of
            # the centre), leaves at once for it: an arc waypoint that lies just past the
            # helix's start may already be behind it, and it would fly a whole lap back to it
            # (benchmarks.reserve, dataset 2 in 10 m/s). Arc waypoints start beyond the count's
            # slack; with none left it leaves on the course to the target.
            angles = leg.arc_angle * np.arange(1, len(arc) + 1) / len(arc)
            arc = arc[angles > math.radians(ARDUPLANE_LAP_SLACK_DEG)]
        # A tangent point on the target itself (no straight part) is the target's own waypoint.
        if len(arc) and np.linalg.norm(arc[-1] - xyz[i + 1]) < 1.0:
            arc = arc[:-1]
        if helix is not None:
            centre, turns, signed = helix
            if firmware == "ardupilot":
                note = f"helix {ids[i]}->{ids[i + 1]}: {turns} turn(s) to {at(centre)['z']:.1f} m"
                add(
                    MAV_CMD_NAV_LOITER_TURNS,
                    mav_frame,
                    note,
                    param1=turns,
                    # 1: leave on the tangent exit once the turns are done, as planned
                    # (common.xml MAV_CMD_NAV_LOITER_TURNS param2 "heading required"; 0 would
                    # let an autopilot leave wherever the turns end; ArduPlane's
                    # verify_loiter_turns waits for the heading either way).
                    param2=1,
                    param3=signed,
                    param4=1,
                    **at(centre),
                )
            elif px4_leaves_on_heading(leg):
                # Helix and arc as one loiter to the altitude of the arc's end, left on the
                # heading to the target: its tangent point is the arc's end (module docstring).
                centre = np.array([centre[0], centre[1], leg.tangent_point[2]])
                note = (
                    f"helix and arc {ids[i]}->{ids[i + 1]}: {turns} turn(s) and "
                    f"{math.degrees(leg.arc_angle):.0f} deg to {at(centre)['z']:.1f} m"
                )
                add(
                    MAV_CMD_NAV_LOITER_TO_ALT,
                    mav_frame,
                    note,
                    param1=1,
                    param2=signed,
                    param4=1,
                    **at(centre),
                )
                arc = arc[:0]
            else:
                # A target beside the circle: no exit heading to ask for, so no loiter (it would
                # end wherever the altitude comes in); the helix as waypoints, like an arc.
                pts = helix_waypoints(leg)
                accept = _arc_acceptance(leg, capture)
                for j, p in enumerate(pts):
                    note = f"helix {ids[i]}->{ids[i + 1]} {j + 1}/{len(pts)} ({turns} turn(s))"
                    add(MAV_CMD_NAV_WAYPOINT, mav_frame, note, param2=accept, **at(p))
        arc_accept = _arc_acceptance(leg, capture)
        for j, p in enumerate(arc):
            note = f"arc {ids[i]}->{ids[i + 1]} {j + 1}/{len(arc)}"
            add(MAV_CMD_NAV_WAYPOINT, mav_frame, note, param2=arc_accept, **at(p))
        label = "B" if i == n_legs - 1 else "correction"
        note = f"{label} {ids[i + 1]}"
        seq = add(MAV_CMD_NAV_WAYPOINT, mav_frame, note, param2=capture, param3=0, **at(xyz[i + 1]))
        point_seqs.append((ids[i + 1], seq))

    beyond = _departure_beyond_b(params, legs[-1], radius, source)
    if beyond is None and firmware == "px4":
        beyond = _px4_run_out_beyond_b(plan, legs[-1], radius, speed, org.alt, source)
    if beyond is not None:
        # B overflown straight on too: an autopilot that switches to the end action early (PX4
        # turns into its loiter at its switch distance) would pass B outside its capture radius.
        note = f"departure {ids[-1]} ({float(np.linalg.norm(beyond[:2] - xyz[-1][:2])):.0f} m on)"
        add(MAV_CMD_NAV_WAYPOINT, mav_frame, note, param2=capture, **at(beyond))
    b = at(xyz[-1])
    if at_end == "loiter":
        # MAVLink: a positive loiter radius is clockwise; 0 leaves the autopilot's own radius.
        signed = float(-last_turn_sense(legs) * radius) if radius > 0 else 0.0
        add(MAV_CMD_NAV_LOITER_UNLIM, mav_frame, "end: loiter at B", param3=signed, **b)
    elif at_end == "rtl":
        add(MAV_CMD_NAV_RETURN_TO_LAUNCH, MAV_FRAME_MISSION, "end: return to launch")
    else:
        # Maritime: the surface at B is sea level, 0 m AMSL.
        add(MAV_CMD_NAV_LAND, mav_frame, "end: land at B", x=b["x"], y=b["y"], z=0.0 - alt_offset)

    return Mission(
        items=tuple(items),
        firmware=firmware,
        home=(float(home_lat), float(home_lon), float(home_alt)),
        cruise_speed=speed,
        turn_radius=radius,
        loiter_param=(LOITER_RADIUS_PARAM[firmware][0], radius) if radius > 0 else None,
        acceptance_radius=float(capture),
        origin=org,
        origin_is_default=org_default,
        altitude_frame=altitude_frame,
        at_end=at_end,
        route_index=k,
        route=tuple(ids),
        point_seqs=tuple(point_seqs),
    )


def _departure_beyond_b(
    params: dict, last: FlownLeg, radius: float, source: str
) -> np.ndarray | None:
    """Where the run-out beyond B ends (B's altitude, along the heading the last leg arrives
    with), or None when the plan has no run-out (``parameters.departure``, 0 in earlier plan
    files) or straight legs."""
    try:
        departure = float(params.get("departure", 0.0))
    except (TypeError, ValueError) as exc:
        raise _bad("parameters.departure must be a number", source, "departure") from exc
    if not math.isfinite(departure) or departure < 0:
        raise _bad(f"parameters.departure must be >= 0, got {departure!r}", source, "departure")
    if departure <= 0 or radius <= 0 or not isinstance(last, AirplaneLeg):
        return None
    return _straight_on_beyond_b(last, departure)


def _straight_on_beyond_b(last: FlownLeg, run_out: float) -> np.ndarray:
    """The point ``run_out`` metres beyond B on the heading the last leg arrives with, at B's
    altitude."""
    out = np.asarray(last.heading_out, dtype=float)
    return np.array([*(last.end[:2] + run_out * out[:2]), last.end[2]])


def _px4_run_out_beyond_b(
    plan: dict, last: FlownLeg, radius: float, eas: float, base_alt: float, source: str = ""
) -> np.ndarray | None:
    """Where a run-out beyond B ends for PX4 when the plan has none: PX4 switches to its next
    item npfg's switch distance early (Navigator::get_acceptance_radius), so with the end
    action next it turns away before B and passes it outside the capture radius (the bundled
    missions/jsbsim in still air: 7.9 m off). Nothing is planned after B, so the run-out costs
    the plan nothing: npfg's settle distance (its track error bound, as a derived plan's run-out
    at every landmark) at the ground speed, B's TAS for ``eas`` plus the plan's design wind.
    None for straight legs."""
    if radius <= 0 or not isinstance(last, AirplaneLeg):
        return None
    from gcs_planner.aircraft.autopilot import effective
    from gcs_planner.aircraft.profile import tas_from_eas

    ground_speed = tas_from_eas(eas, float(last.end[2]) + base_alt) + plan_design_wind(plan, source)
    return _straight_on_beyond_b(last, effective("px4", {}).settle_distance(ground_speed))


def _arc_acceptance(leg: FlownLeg, capture: int) -> float:
    """param2 of the waypoints on a leg's circle: the autopilot must pass close to them, not cut
    inside the turn, so at most a quarter of the spacing between them."""
    chord = 2.0 * leg.radius * math.sin(arc_step(leg.radius) / 2.0)
    return float(max(1, min(capture, math.floor(chord / 4.0))))


def _deg_e7(deg: float) -> int:
    return int(round(float(deg) * 1e7))
