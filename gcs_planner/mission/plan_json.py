"""The plan JSON: the contract between `plan` and everything that reads a plan (docs/plan-json.md).

Readers (exporter, link, other tools) see only this dict, never the search's objects.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from gcs_planner.aircraft.profile import TRACKING_ALLOWANCE_M
from gcs_planner.core.capture import capture_check, capture_warning
from gcs_planner.core.planner import Plan
from gcs_planner.core.route import Route
from gcs_planner.errors import InputError
from gcs_planner.geometry.trajectory import leg_to_dict, scenario_trajectory
from gcs_planner.scenario.model import Kind, Scenario, altitude_of

FORMAT = "gcs-planner-plan"
VERSION = 1


def route_to_dict(
    scenario: Scenario, route: Route, lower_bound: float, settled: bool = True
) -> dict[str, Any]:
    """One front route. ``settled``: no open partial route may still lead to a front route with
    no more corrections or a higher probability (see ``core.proof``); "optimal" needs it."""
    trajectory = scenario_trajectory(scenario, route.points)
    legs = []
    for prev, stop, geo in zip(route.stops[:-1], route.stops[1:], trajectory.legs):
        legs.append(
            {
                "from": prev.id,
                "to": stop.id,
                "kind": stop.kind.name,
                "unreliable": stop.unreliable,
                "length": stop.leg.length,
                "arc": stop.leg.arc,
                "straight": stop.leg.straight,
                "turn_angle_deg": math.degrees(stop.leg.turn_angle),
                "path_angle_deg": stop.leg.path_angle,
                "helix_turns": stop.leg.helix_turns,
                "cumulative": stop.cumulative,
                "v_error": stop.v_arrival,
                "h_error": stop.h_arrival,
                "v_limit": stop.v_limit,
                "h_limit": stop.h_limit,
                "v_margin": stop.v_margin,
                "h_margin": stop.h_margin,
                "p_arrive": stop.p_arrive,
                "geometry": leg_to_dict(geo),
            }
        )
    gap = max(0.0, route.length - lower_bound)
    return {
        "length": route.length,
        "corrections": route.corrections,
        "probability": route.probability,
        "optimal": settled and gap <= 1e-6,
        "gap": gap,
        "lower_bound": lower_bound,
        "route": route.ids(),
        "legs": legs,
    }


def capture_of(plan: Plan) -> dict[str, Any]:
    """The capture check of the chosen route (:func:`gcs_planner.core.capture.capture_check`), with
    its warning (None when every correction point fits its capture radius)."""
    s = plan.scenario
    check = capture_check(
        plan.route.stops, s.error_unit, s.capture_radius, TRACKING_ALLOWANCE_M, s.params
    )
    return {**check, "warning": capture_warning(check)}


def reserve_of(plan: Plan) -> dict[str, Any]:
    """The flight reserve the plan was made with, where it came from and, when derived, its
    derivation and the chosen route's own stretches checked against it (flight_reserve.py)."""
    s = plan.scenario
    metres = s.params.reserve
    source = s.reserve_source or ("stated" if metres > 0 else "none")
    out: dict[str, Any] = {"metres": metres, "source": source}
    basis = s.reserve_basis
    if basis is not None:
        out.update(basis.to_dict())
        out["metres"] = metres
        if plan.routes:
            need, frm, to = basis.route_check(plan.route, altitude_of(s))
            out["chosen_route"] = {
                "need_m": need, "from": frm, "to": to, "covered": need <= metres + 1e-9,
            }  # fmt: skip
    return out


def endurance_of(plan: Plan) -> dict[str, Any]:
    """The endurance planned for and the flight minutes of the chosen route and the front."""
    from gcs_planner.core.flight_time import route_minutes

    minutes = [route_minutes(plan.scenario, r) for r in plan.routes]
    return {
        "minutes": plan.scenario.endurance,
        "chosen_flight_minutes": minutes[plan.chosen],
        "front_flight_minutes": minutes,
    }


def plan_to_dict(plan: Plan) -> dict[str, Any]:
    s = plan.scenario
    origin = (
        None
        if s.origin is None
        else {"lat": s.origin.lat, "lon": s.origin.lon, "alt": s.origin.alt}
    )
    return {
        "format": FORMAT,
        "version": VERSION,
        "scenario": {
            "name": s.name,
            "source": s.source,
            "points": s.n,
            "origin": origin,
            # No origin: readers place the frame at the default one (and warn); say so.
            "origin_is_default": origin is None,
            "heading_at_a": None if s.heading_at_a is None else list(s.heading_at_a),
            # Metres flown since the last vertical / horizontal reset at A: (0, 0) at a
            # mission's start, a state's errors for a plan made from it (plan --from-state).
            "initial_errors": list(s.initial_errors),
        },
        "parameters": s.params.to_dict(),
        # parameters.reserve with where it came from and, when derived, how.
        "reserve": reserve_of(plan),
        "vehicle": {
            "leg_model": s.vehicle.leg_model,
            "cruise_airspeed": s.vehicle.cruise_airspeed,
            "bank_angle_deg": s.vehicle.bank_angle,
            "radius_source": s.vehicle.radius_source,
            "description": s.vehicle.describe(),
            # How the radius and angles were derived from the autopilot's terms and the
            # design wind (None: stated directly or assumed).
            "envelope": None if s.envelope is None else s.envelope.to_dict(),
        },
        # The minutes of flight the aircraft has (None: unlimited) and the flight time of each
        # front route in the design wind (core/flight_time.py); the dry run judges against it.
        "endurance": endurance_of(plan),
        "warnings": list(plan.warnings),
        "objectives": list(plan.objectives),
        "front": [
            route_to_dict(s, r, lb, ok)
            for r, lb, ok in zip(plan.routes, plan.lower_bounds, plan.proven())
        ],
        "chosen": plan.chosen,
        # The chosen route's errors on arrival, in metres, against the capture radius.
        "capture": capture_of(plan),
        "choice": plan.choice,
        "min_probability": plan.min_probability,
        "threshold_met": plan.threshold_met,
        "shortest_certain": plan.shortest_certain,
        "most_reliable": plan.most_reliable,
        "optimality": {"optimal": plan.optimal, "statement": plan.statement},
        "stats": plan.stats,
        "points": [
            {
                "id": s.ids[i],
                "x": float(s.xyz[i, 0]),
                "y": float(s.xyz[i, 1]),
                "z": float(s.xyz[i, 2]),
                "kind": Kind(int(s.kind[i])).name,
                "unreliable": bool(s.unreliable[i]),
            }
            for i in range(s.n)
        ],
    }


def dumps_dict(data: dict[str, Any]) -> str:
    return json.dumps(data, indent=1, allow_nan=False) + "\n"


def dumps(plan: Plan) -> str:
    return dumps_dict(plan_to_dict(plan))


def read_json(path: str | Path, what: str) -> Any:
    """The JSON value in ``path``; InputError naming the file when it is missing or not JSON
    (``what``: "plan JSON", "policy JSON", for the message)."""
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError("no such file", file=str(path)) from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"not a readable {what} ({exc})", file=str(path)) from None


def load_plan(path: str | Path) -> dict[str, Any]:
    """Read a plan JSON file, checking that it is one (clear error otherwise)."""
    data = read_json(path, "plan JSON")
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise InputError(
            f'not a gcs-planner plan (expected "format": "{FORMAT}")',
            file=str(path),
            field="format",
        )
    if data.get("version") != VERSION:
        raise InputError(
            f"unsupported plan version {data.get('version')!r}", file=str(path), field="version"
        )
    front = data.get("front")
    if not isinstance(front, list) or not front:
        raise InputError("the plan has no routes", file=str(path), field="front")
    # What every reader needs (docs/plan-json.md): the georeference, the parameters, each
    # route's points and legs. The mission builder's plan reading owns the checks, so an upload
    # of a plan JSON (which reads it without this function) refuses the same damage.
    from gcs_planner.mission.plan_reading import check_plan

    check_plan(data, str(path))
    return data
