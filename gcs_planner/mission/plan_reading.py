"""Reading a plan JSON (docs/plan-json.md) for the exporters: its checks, the route of its front
to export with that route's legs and points, its georeference, and the cruise airspeed and
design wind its envelope was made for. Every refusal is an InputError naming the field."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from gcs_planner.aircraft.profile import DEFAULT_CRUISE_AIRSPEED
from gcs_planner.errors import InputError
from gcs_planner.geometry.legs import FlownLeg
from gcs_planner.geometry.trajectory import leg_from_dict
from gcs_planner.scenario.georef import DEFAULT_ORIGIN, validate_origin
from gcs_planner.scenario.model import Origin

PLAN_FORMAT = "gcs-planner-plan"
PLAN_VERSION = 1


def plan_error(message: str, source: str, field: str | None = None) -> InputError:
    """The InputError for ``message``, naming the plan file ``source`` and the ``field``."""
    return InputError(message, file=source, field=field)


def check_plan(plan: Any, source: str = "") -> None:
    """Raise InputError unless ``plan`` looks like a plan JSON this module can read."""
    if not isinstance(plan, dict):
        raise plan_error("not a plan: expected a JSON object", source)
    if plan.get("format") != PLAN_FORMAT:
        raise plan_error(f"not a plan: 'format' must be {PLAN_FORMAT!r}", source, "format")
    if plan.get("version") != PLAN_VERSION:
        raise plan_error(
            f"unsupported plan version {plan.get('version')!r} (this reader knows {PLAN_VERSION})",
            source,
            "version",
        )
    front = plan.get("front")
    if not isinstance(front, list) or not front:
        raise plan_error("the plan has no route: 'front' must be a non-empty list", source, "front")
    chosen = plan.get("chosen")
    if isinstance(chosen, bool) or not isinstance(chosen, int) or not 0 <= chosen < len(front):
        raise plan_error(
            f"'chosen' must be an index into 'front' (0..{len(front) - 1}), got {chosen!r}",
            source,
            "chosen",
        )
    scenario = plan.get("scenario")
    if not isinstance(scenario, dict):
        raise plan_error("'scenario' must be an object (docs/plan-json.md)", source, "scenario")
    # A plan that lost its origin must not be exported to the default one: that puts the
    # mission tens of kilometres from its landmarks. `null` is how a plan says it has none.
    if "origin" not in scenario:
        raise plan_error(
            "the plan has lost its georeference: 'scenario.origin' must be there, an object "
            "{lat, lon, alt} or null (re-run `gcs-planner plan` to write it again)",
            source,
            "scenario.origin",
        )
    is_default = scenario.get("origin_is_default", False)
    if not isinstance(is_default, bool):
        raise plan_error(
            f"'scenario.origin_is_default' must be true or false, got {is_default!r}",
            source,
            "scenario.origin_is_default",
        )
    resolve_origin(plan, None, source)  # an origin of numbers in range, not contradicted
    params = plan.get("parameters")
    if not isinstance(params, dict):
        raise plan_error("'parameters' must be an object (docs/plan-json.md)", source, "parameters")
    if "turn_radius" not in params:
        raise plan_error("'parameters.turn_radius' is missing", source, "parameters.turn_radius")
    radius = params["turn_radius"]
    if not _is_number(radius) or not radius >= 0:
        raise plan_error(
            f"'parameters.turn_radius' must be a finite number of metres >= 0 (0: straight "
            f"legs), got {radius!r}",
            source,
            "parameters.turn_radius",
        )
    points = plan.get("points")
    if points is not None and not isinstance(points, list):
        raise plan_error("'points' must be a list of points", source, "points")
    ids = None if points is None else {str(q.get("id")) for q in points if isinstance(q, dict)}
    for k, entry in enumerate(front):
        _check_entry(entry, k, ids, source)


def _check_entry(entry: Any, k: int, ids: set[str] | None, source: str) -> None:
    """One route of the front: its points and one leg per point after A, each point in the
    plan's points table (a route through a point the plan does not have contradicts it)."""
    if not isinstance(entry, dict):
        raise plan_error(f"front[{k}] is not an object", source, "front")
    route, legs = entry.get("route"), entry.get("legs")
    if not isinstance(route, list) or len(route) < 2:
        raise plan_error(
            f"front[{k}].route must list at least A and B", source, f"front[{k}].route"
        )
    if not isinstance(legs, list) or len(legs) != len(route) - 1:
        raise plan_error(
            f"front[{k}].legs must have one leg per point after A", source, f"front[{k}].legs"
        )
    if ids is not None:
        missing = [str(pid) for pid in route if str(pid) not in ids]
        if missing:
            raise plan_error(
                f"front[{k}].route goes through point {missing[0]!r}, which 'points' does not have",
                source,
                f"front[{k}].route",
            )
    _check_figures(entry, f"front[{k}]", source, required=("length",))
    corrections = entry.get("corrections", 0)
    if isinstance(corrections, bool) or not isinstance(corrections, int) or corrections < 0:
        raise plan_error(
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
            raise plan_error(f"{where}.{name} must be {want}, got {got}", source, f"{where}.{name}")


def route_entry(plan: dict, route_index: int | None = None, source: str = "") -> tuple[int, dict]:
    """(index, entry) of the route to export: ``route_index`` or the plan's chosen one."""
    check_plan(plan, source)
    front = plan["front"]
    k = plan.get("chosen", 0) if route_index is None else route_index
    if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(front):
        field = "chosen" if route_index is None else "--route-index"
        raise plan_error(
            f"route index {k!r} is not in the front (0..{len(front) - 1})", source, field
        )
    entry = front[k]
    if not isinstance(entry, dict):
        raise plan_error(f"front[{k}] is not an object", source, "front")
    route, legs = entry.get("route"), entry.get("legs")
    if not isinstance(route, list) or len(route) < 2:
        raise plan_error(f"front[{k}].route must list at least A and B", source, "route")
    if not isinstance(legs, list) or len(legs) != len(route) - 1:
        raise plan_error(f"front[{k}].legs must have one leg per point after A", source, "legs")
    return k, entry


def route_legs(entry: dict, source: str = "") -> list[FlownLeg]:
    """The flown legs of a front entry, from their ``geometry``."""
    out = []
    for i, leg in enumerate(entry["legs"]):
        try:
            out.append(leg_from_dict(leg.get("geometry") if isinstance(leg, dict) else None))
        except ValueError as exc:
            raise plan_error(f"legs[{i}].geometry: {exc}", source, "geometry") from exc
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
            raise plan_error(f"point {pid!r} needs numbers x, y, z", source, "points") from exc
    if not np.all(np.isfinite(out)):
        raise plan_error("route points must have finite coordinates", source, "points")
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
            raise plan_error(
                f"scenario.origin must have numbers lat, lon[, alt]: {o!r}", source, field
            ) from exc
        given = validate_origin(given, file=source, field=field)
        is_default = bool(scen.get("origin_is_default", False))
        if is_default and given != DEFAULT_ORIGIN:
            raise plan_error(
                f"scenario.origin {given.lat}, {given.lon} contradicts "
                "'origin_is_default': true (the default origin is "
                f"{DEFAULT_ORIGIN.lat}, {DEFAULT_ORIGIN.lon})",
                source,
                "scenario.origin_is_default",
            )
        return given, is_default
    if o is not None:
        raise plan_error(f"scenario.origin must be an object or null, got {o!r}", source, field)
    return DEFAULT_ORIGIN, True


def plan_cruise_airspeed(plan: dict, source: str = "") -> float:
    """The cruise airspeed (m/s EAS) the plan's envelope was made for: ``vehicle.cruise_airspeed``
    (the default airspeed in plan files of releases that did not write it)."""
    vehicle = plan.get("vehicle")
    if not isinstance(vehicle, dict) or "cruise_airspeed" not in vehicle:
        return DEFAULT_CRUISE_AIRSPEED
    try:
        speed = float(vehicle["cruise_airspeed"])
    except (TypeError, ValueError) as exc:
        raise plan_error(
            f"vehicle.cruise_airspeed must be a number, got {vehicle['cruise_airspeed']!r}",
            source,
            "vehicle.cruise_airspeed",
        ) from exc
    if not math.isfinite(speed) or not 0.0 < speed <= 1000.0:
        raise plan_error(
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
        raise plan_error(
            "vehicle.envelope.design_wind must be a number",
            source,
            "vehicle.envelope.design_wind",
        ) from exc
    if not math.isfinite(wind) or wind < 0:
        raise plan_error(
            f"vehicle.envelope.design_wind must be >= 0 m/s, got {wind!r}",
            source,
            "vehicle.envelope.design_wind",
        )
    return wind
