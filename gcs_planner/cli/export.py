"""`gcs-planner export PLAN.json --format F --out FILE`: one file from an earlier plan."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gcs_planner.aircraft.autopilot import AUTOPILOTS, DEFAULT_AUTOPILOT
from gcs_planner.cli.common import add_autopilot_argument
from gcs_planner.core.choose import DEFAULT_MIN_PROBABILITY
from gcs_planner.errors import InputError
from gcs_planner.mission.builder import (
    ALTITUDE_FRAMES,
    DEFAULT_ACCEPTANCE_RADIUS,
    DEFAULT_CRUISE_SPEED,
    END_ACTIONS,
)
from gcs_planner.mission.export import FORMATS, export
from gcs_planner.mission.param_files import SETUP_FILES, render_setup
from gcs_planner.mission.vehicle_setup import needs as setup_needs
from gcs_planner.runtime.atomic import write_atomic
from gcs_planner.scenario.georef import DEFAULT_ORIGIN_WARNING, parse_home, parse_origin


def add_mission_arguments(p: argparse.ArgumentParser) -> None:
    """The mission options, shared with any command that builds a mission from a plan."""
    g = p.add_argument_group("mission")
    g.add_argument("--route-index", type=int, help="route of the front (default: the chosen one)")
    # --firmware is its old name, kept as a deprecated alias.
    add_autopilot_argument(
        g,
        help="the autopilot the mission is for (default: the one the plan was made for, "
        f"plan.json's setup.autopilot; else {DEFAULT_AUTOPILOT})",
    )
    g.add_argument(
        "--altitude-frame",
        choices=tuple(ALTITUDE_FRAMES),
        default="amsl",
        help="amsl: MAV_FRAME_GLOBAL (default); relative: MAV_FRAME_GLOBAL_RELATIVE_ALT, "
        "metres above the home given with --home (required with relative)",
    )
    g.add_argument(
        "--home",
        metavar="LAT,LON,ALT",
        help="where the aircraft is armed (ALT: metres above mean sea level): the home the "
        "mission files carry and what relative altitudes are measured from (default: A)",
    )
    # The autopilot's waypoint ACCEPTANCE radius (param2), not the landmark's CAPTURE radius;
    # --capture-radius is its old, misleading name, kept as a deprecated alias.
    g.add_argument(
        "--acceptance-radius",
        "--capture-radius",
        dest="acceptance_radius",
        type=float,
        default=DEFAULT_ACCEPTANCE_RADIUS,
        help="waypoint acceptance radius of the correction waypoints, whole metres "
        f"(default {DEFAULT_ACCEPTANCE_RADIUS}; --capture-radius is a deprecated alias)",
    )
    g.add_argument(
        "--cruise-speed",
        type=float,
        default=None,
        help="airspeed in m/s the mission sets (DO_CHANGE_SPEED; default: the plan's cruise "
        f"airspeed, which its climb angles and turning radius were derived for; "
        f"{DEFAULT_CRUISE_SPEED:g} for plan files without one)",
    )
    g.add_argument("--at-end", choices=END_ACTIONS, default="loiter", help="action at B")
    g.add_argument("--origin", help="georeference LAT,LON[,ALT] (overrides the plan's)")


def mission_options(args: argparse.Namespace, source: str = "") -> dict:
    return {
        "route_index": args.route_index,
        "firmware": args.autopilot,
        "altitude_frame": args.altitude_frame,
        "acceptance_radius": args.acceptance_radius,
        "cruise_speed": args.cruise_speed,
        "at_end": args.at_end,
        "origin": None if args.origin is None else parse_origin(args.origin),
        "home": None if args.home is None else parse_home(args.home),
        "source": source,
    }


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "export",
        help="convert a plan JSON to a mission file, a map file or a picture",
        description="Convert an earlier plan (plan.json) to one file: a QGroundControl .plan, "
        "a Mission Planner .waypoints, KML, GeoJSON, the route table as CSV, or a PNG (png: the "
        "route in 3D with its projections; front-png: the Pareto front).",
    )
    p.add_argument("plan", type=Path, help="plan JSON written by `gcs-planner plan`")
    p.add_argument("--format", required=True, choices=tuple(FORMATS), dest="fmt")
    p.add_argument("--out", required=True, type=Path, help="file to write")
    add_mission_arguments(p)
    add_risk_arguments(p)
    p.set_defaults(func=run)


def add_risk_arguments(p: argparse.ArgumentParser) -> None:
    """--min-probability and --allow-risky: a route less likely to arrive than the plan asked
    for is exported only when the user says so."""
    g = p.add_argument_group("risk")
    g.add_argument(
        "--min-probability",
        type=float,
        metavar="P",
        help="refuse a route less likely than P to arrive (default: the plan's own, "
        f"{DEFAULT_MIN_PROBABILITY:g} unless it was planned with another)",
    )
    g.add_argument(
        "--allow-risky",
        action="store_true",
        help="export the route even below --min-probability (a warning names its probability)",
    )


def risk_check(args: argparse.Namespace, plan: dict) -> str | None:
    """The warning to print for the route being exported, or RiskyRouteError (see policy)."""
    from gcs_planner.core.choose import check_exportable

    k = plan["chosen"] if args.route_index is None else args.route_index
    if not isinstance(k, int) or not 0 <= k < len(plan["front"]):
        return None  # the exporter names the bad index
    floor = args.min_probability
    if floor is None:
        floor = plan.get("min_probability", DEFAULT_MIN_PROBABILITY)
    if not isinstance(floor, (int, float)) or not 0.0 <= floor <= 1.0:
        raise InputError(f"{floor!r} is not a probability (0 to 1)", field="--min-probability")
    probability = plan["front"][k].get("probability", 1.0)
    if not isinstance(probability, (int, float)):
        raise InputError(f"front[{k}].probability is not a number", field="probability")
    return check_exportable(float(probability), k, float(floor), args.allow_risky)


# The suffixes that say which file a name is: an --out ending in another format's (a KML
# named x.plan) is a mistake that a ground station would find later, loading it as a mission.
# Other suffixes (none, .txt, .json, ...) are the user's choice.
SUFFIXES = {
    "plan": (".plan",),
    "waypoints": (".waypoints",),
    "geojson": (".geojson",),
    "kml": (".kml",),
    "csv": (".csv",),
    "png": (".png",),
    "front-png": (".png",),
    "error-budget-png": (".png",),
}


def check_out_suffix(fmt: str, out: Path) -> None:
    """InputError naming --out when its suffix is another format's."""
    suffix = out.suffix.lower()
    own = SUFFIXES.get(fmt, ())
    others = [f for f, ends in SUFFIXES.items() if suffix in ends and f != fmt]
    if not others or suffix in own:
        return
    raise InputError(
        f"ends in {suffix}, a {' or '.join(others)} file, but --format {fmt} writes "
        f"{' or '.join(own)}: name it {out.with_suffix(own[0]).name} or give --format "
        f"{others[0]}",
        file=str(out),
        field="--out",
    )


# The formats that are missions an autopilot flies: the vehicle setup is written beside them.
MISSION_FORMATS = ("plan", "waypoints")


def plan_autopilot(plan: dict) -> str:
    """The autopilot ``plan`` (a plan JSON) was made for: its setup's, else ArduPilot."""
    setup = plan.get("setup")
    name = setup.get("autopilot") if isinstance(setup, dict) else None
    return name if name in AUTOPILOTS else DEFAULT_AUTOPILOT


def run(args: argparse.Namespace) -> int:
    from gcs_planner.mission.plan_json import load_plan
    from gcs_planner.runtime.atomic import check_output_file

    check_out_suffix(args.fmt, args.out)
    check_output_file(args.out)
    plan = load_plan(args.plan)
    args.autopilot = args.autopilot or plan_autopilot(plan)
    warning = risk_check(args, plan)
    setup = setup_needs(plan, args.autopilot) if args.fmt in MISSION_FORMATS else []
    unflyable = [f"{n.name}: {n.impossible}" for n in setup if n.impossible]
    if unflyable:
        from gcs_planner.core.choose import RiskyRouteError

        cannot = f"no {args.autopilot} setup flies this plan ({'; '.join(unflyable)})"
        if not args.allow_risky:
            raise RiskyRouteError(f"{cannot}; not exported: pass --allow-risky to export it")
        warning = f"{warning}; {cannot}" if warning else cannot
    path, mission = export(plan, args.fmt, args.out, **mission_options(args, str(args.plan)))
    print(f"wrote {path} (route {mission.route_index}, {len(mission.items)} mission items)")
    if setup:
        # The vehicle setup the mission relies on, beside it (as plan --out writes it).
        for name, text in render_setup(setup, args.autopilot, str(args.plan)):
            write_atomic(path.parent / name, text)
        print(f"wrote the vehicle setup for {args.autopilot} beside it: {', '.join(SETUP_FILES)}")
    if warning:
        print(f"gcs-planner: warning: {warning}", file=sys.stderr)
    if mission.origin_is_default:
        print(f"gcs-planner: warning: {DEFAULT_ORIGIN_WARNING}", file=sys.stderr)
    return 0
