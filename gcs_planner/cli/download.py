"""`gcs-planner download --connect CONN --out FILE`: the vehicle's mission to a file."""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict
from pathlib import Path

from gcs_planner.atomic import write_atomic
from gcs_planner.cli.upload import add_link_arguments, connect_client
from gcs_planner.errors import InputError
from gcs_planner.mission.items import MissionItem


def _items_json(items: list[MissionItem], firmware: str) -> str:
    rows = []
    for it in items:
        row = asdict(it)
        row.pop("note", None)
        rows.append(row)
    return json.dumps({"firmware": firmware, "items": rows}, indent=2) + "\n"


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    suffix = out.suffix.lower()
    if suffix not in (".waypoints", ".json"):
        raise InputError("expected a .waypoints or .json output file", file=str(out), field="--out")
    client = connect_client(args)
    try:
        items = client.download()
        firmware = client.firmware or "generic"
    finally:
        client.link.close()
    if suffix == ".json":
        write_atomic(out, _items_json(items, firmware))
    else:
        write_atomic(out, _waypoints_text(items))
    print(f"downloaded {len(items)} items from system {client.target_system} to {out}")
    return 0


_GLOBAL_FRAMES = (0, 3, 5, 6, 10, 11)


def _lat_lon(it: MissionItem) -> tuple[str, str]:
    if it.frame in _GLOBAL_FRAMES:
        return f"{it.x / 1e7:.8f}", f"{it.y / 1e7:.8f}"
    return f"{it.x:.8f}", f"{it.y:.8f}"


def _waypoints_text(items: list[MissionItem]) -> str:
    """Mission Planner's QGC WPL 110: index, current, frame, command, params 1-4, lat, lon,
    alt, autocontinue, tab-separated."""
    lines = ["QGC WPL 110"]
    for i, it in enumerate(items):
        fields = [
            i,
            it.current,
            it.frame,
            it.command,
            *(f"{p:.8f}" for p in (it.param1, it.param2, it.param3, it.param4)),
            *_lat_lon(it),
            f"{it.z:.6f}",
            it.autocontinue,
        ]
        lines.append("\t".join(str(f) for f in fields))
    return "\n".join(lines) + "\n"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "download",
        help="download the vehicle's mission to a file",
        description="Read the mission a vehicle holds over MAVLink and write it as .waypoints "
        "or JSON.",
    )
    add_link_arguments(p)
    p.add_argument("--out", required=True, help="output file: .waypoints or .json")
    p.set_defaults(func=run)
