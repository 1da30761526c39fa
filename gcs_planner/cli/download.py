"""`gcs-planner download --connect CONN --out FILE`: the vehicle's mission to a file."""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict
from pathlib import Path

from gcs_planner.aircraft.autopilot import AUTOPILOTS, keeps_home_item
from gcs_planner.cli.upload import add_link_arguments, connect_client
from gcs_planner.errors import InputError, LinkError
from gcs_planner.mission.items import GLOBAL_FRAMES, POSITION_COMMANDS, MissionItem
from gcs_planner.mission.waypoints import PX4_REFUSED, dumps_items
from gcs_planner.runtime.atomic import check_output_file, write_atomic


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
    check_output_file(out)
    client = connect_client(args)
    try:
        items = client.download()
        firmware = client.firmware or "generic"
    except LinkError as exc:
        raise LinkError(f"{exc}; nothing was written to {out}") from None
    finally:
        client.link.close()
    if suffix == ".json":
        write_atomic(out, _items_json(items, firmware))
    elif firmware in AUTOPILOTS and not AUTOPILOTS[firmware].home_at_seq0:
        # The export's rule, for the same reason: readers disagree on a .waypoints row 0 of an
        # autopilot that keeps no home item (PX4).
        raise InputError(
            PX4_REFUSED.replace("use --format plan (QGroundControl .plan)", "use --out FILE.json")
            + f"; nothing was written to {out}",
            file=str(out),
            field="--out",
        )
    else:
        try:
            home = _home(items, firmware)
        except LinkError as exc:
            raise LinkError(f"{exc}; nothing was written to {out}") from None
        write_atomic(out, dumps_items(items, firmware, home))
    how = " by MAVFTP" if client.transfer_used == "ftp" else ""
    print(f"downloaded {len(items)} items from system {client.target_system}{how} to {out}")
    return 0


def _home(items: list[MissionItem], firmware: str) -> tuple[float, float, float]:
    """Row 0 of a .waypoints file is home. ArduPilot sends it as item 0 (so item 0 must be a
    place: any other item there would be lost, or a parameter read as a latitude); PX4 has no
    home item, so the first position item's stands in for it (what a reader sees as home)."""
    if keeps_home_item(firmware) and items:
        home = items[0]
        if home.command not in POSITION_COMMANDS or home.frame not in GLOBAL_FRAMES:
            raise LinkError(
                "the vehicle sent an invalid mission item: seq 0, field 'command': ArduPilot's "
                f"item 0 is home, a position, but it is command {home.command} in frame "
                f"{home.frame}"
            )
        return (home.x / 1e7, home.y / 1e7, home.z)
    # The first item with a position: a DO_ item's x/y are parameters, not a latitude.
    for it in items:
        if it.command in POSITION_COMMANDS and it.frame in GLOBAL_FRAMES:
            return (it.x / 1e7, it.y / 1e7, it.z)
    return (0.0, 0.0, 0.0)


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
