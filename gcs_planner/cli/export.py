"""`gcs-planner export PLAN.json --format F --out FILE`: one file from an earlier plan."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gcs_planner.mission.builder import (
    ALTITUDE_FRAMES,
    DEFAULT_CAPTURE_RADIUS,
    DEFAULT_CRUISE_SPEED,
    END_ACTIONS,
    FIRMWARES,
)
from gcs_planner.mission.export import FORMATS, export
from gcs_planner.mission.georef import DEFAULT_ORIGIN_WARNING, parse_origin


def add_mission_arguments(p: argparse.ArgumentParser) -> None:
    """The mission options, shared with any command that builds a mission from a plan."""
    g = p.add_argument_group("mission")
    g.add_argument("--route-index", type=int, help="route of the front (default: the chosen one)")
    g.add_argument("--firmware", choices=FIRMWARES, default="ardupilot", help="default ardupilot")
    g.add_argument(
        "--altitude-frame",
        choices=tuple(ALTITUDE_FRAMES),
        default="amsl",
        help="amsl: MAV_FRAME_GLOBAL (default); relative: MAV_FRAME_GLOBAL_RELATIVE_ALT, "
        "above home at A",
    )
    g.add_argument(
        "--capture-radius",
        type=float,
        default=DEFAULT_CAPTURE_RADIUS,
        help="acceptance radius of the correction waypoints, whole metres "
        f"(default {DEFAULT_CAPTURE_RADIUS})",
    )
    g.add_argument(
        "--cruise-speed",
        type=float,
        default=DEFAULT_CRUISE_SPEED,
        help=f"airspeed in m/s (default {DEFAULT_CRUISE_SPEED:g})",
    )
    g.add_argument("--at-end", choices=END_ACTIONS, default="loiter", help="action at B")
    g.add_argument("--origin", help="georeference LAT,LON[,ALT] (overrides the plan's)")


def mission_options(args: argparse.Namespace, source: str = "") -> dict:
    return {
        "route_index": args.route_index,
        "firmware": args.firmware,
        "altitude_frame": args.altitude_frame,
        "capture_radius": args.capture_radius,
        "cruise_speed": args.cruise_speed,
        "at_end": args.at_end,
        "origin": None if args.origin is None else parse_origin(args.origin),
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
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from gcs_planner.atomic import check_output_file
    from gcs_planner.plan_json import load_plan

    check_output_file(args.out)
    plan = load_plan(args.plan)
    path, mission = export(plan, args.fmt, args.out, **mission_options(args, str(args.plan)))
    if mission.origin_is_default:
        print(f"gcs-planner: warning: {DEFAULT_ORIGIN_WARNING}", file=sys.stderr)
    print(f"wrote {path} (route {mission.route_index}, {len(mission.items)} mission items)")
    return 0
