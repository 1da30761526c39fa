"""Mission Planner ``.waypoints`` files (``QGC WPL 110``): writer and reader.

One header line ``QGC WPL 110``, then one line per item, tab-separated, LF line endings:

    INDEX  CURRENT  FRAME  COMMAND  P1  P2  P3  P4  LAT  LON  ALT  AUTOCONTINUE

Row 0 is always home (the ArduPilot convention Mission Planner follows), with CURRENT 1 as Mission
Planner writes it, and row k is ArduPilot's seq k. Latitude and longitude carry 8 decimals
(about 1 mm), altitudes and parameters 6.

A PX4 mission is not written as .waypoints: PX4 has no home item, and the readers disagree on
row 0. QGroundControl reads row 0 of a "QGC WPL 110" file as the planned home and leaves it out
of the mission (MissionController::_loadTextMissionFile), while pymavlink's MAVWPLoader,
MAVProxy's `wp load` and MAVSDK's importer upload every row, row 0 as item 0. Whatever row 0
holds, one side flies a mission the other does not: with a home on the surface, the second
would fly to it at sea level first. A .plan says where home is (plannedHomePosition) and which
firmware it is for, and every reader agrees on it. Reading still takes a PX4 file written by
earlier releases (row 0 home, seq k at row k + 1), as QGroundControl reads it.

Why not pymavlink's ``mavwp.MAVWPLoader`` (read in pymavlink 2.4.50): its ``save`` writes
latitude and longitude with ``%f`` (6 decimals, about 0.1 m, where this keeps 8) straight into
the file opened for writing (a crash or a full disk leaves a cut file, where this writes to a
temporary file and renames it), and knows no autopilot, so it cannot refuse a PX4 mission or
number its rows. Its ``load`` makes each row a MISSION_ITEM, sent with float32 latitude and
longitude (steps of 0.85 m in longitude at 123.5 degrees E), where this keeps the 1e-7 degree
integers of MISSION_ITEM_INT; it renumbers the rows (``add`` sets ``seq`` from the count)
instead of refusing one out of order, takes NaN or infinite positions, turns a row 0 of command
0 into a waypoint, and reports a bad row as "invalid waypoint line with N values" or Python's
own ValueError, without the file, the row or the field.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT, keeps_home_item
from gcs_planner.errors import InputError
from gcs_planner.mission.builder import FIRMWARES, Mission
from gcs_planner.mission.items import (
    GLOBAL_FRAMES,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MissionFile,
    MissionItem,
)
from gcs_planner.runtime.atomic import write_atomic

HEADER = "QGC WPL 110"
FIELDS = (
    "index",
    "current",
    "frame",
    "command",
    "param1",
    "param2",
    "param3",
    "param4",
    "lat",
    "lon",
    "alt",
    "autocontinue",
)


def _row(index: int, current: int, item: MissionItem) -> str:
    if item.frame in GLOBAL_FRAMES:
        lat, lon = f"{item.x / 1e7:.8f}", f"{item.y / 1e7:.8f}"
    else:
        lat, lon = f"{item.x:.8f}", f"{item.y:.8f}"
    cells = [
        str(index),
        str(current),
        str(item.frame),
        str(item.command),
        *(f"{p:.6f}" for p in (item.param1, item.param2, item.param3, item.param4)),
        lat,
        lon,
        f"{item.z:.6f}",
        str(item.autocontinue),
    ]
    return "\t".join(cells)


PX4_REFUSED = (
    "a PX4 mission is not written as .waypoints: QGroundControl reads its row 0 as home and "
    "leaves it out of the mission, pymavlink, MAVProxy and MAVSDK upload row 0 as item 0, so "
    "no row 0 means the same to all of them; use --format plan (QGroundControl .plan)"
)


def dumps_waypoints(mission: Mission) -> str:
    """The mission as a .waypoints text; ArduPilot only (module docstring)."""
    if not keeps_home_item(mission.firmware):
        raise InputError(PX4_REFUSED, field="--autopilot")
    return dumps_items(mission.items, mission.firmware, mission.home)


def dumps_items(
    items: Sequence[MissionItem], firmware: str, home: tuple[float, float, float]
) -> str:
    """Items as the firmware stores them (ArduPilot: home at seq 0) as a .waypoints text, whose
    row 0 is always home."""
    lat, lon, alt = home
    home = MissionItem(
        seq=0,
        frame=MAV_FRAME_GLOBAL,
        command=MAV_CMD_NAV_WAYPOINT,
        x=int(round(lat * 1e7)),
        y=int(round(lon * 1e7)),
        z=alt,
    )
    rest = items[1:] if keeps_home_item(firmware) else items
    lines = [HEADER, _row(0, 1, home)]
    lines += [_row(k + 1, item.current, item) for k, item in enumerate(rest)]
    return "\n".join(lines) + "\n"


def write_waypoints(mission: Mission, path: str | os.PathLike[str]) -> Path:
    """Write the mission as a Mission Planner .waypoints file, atomically."""
    return write_atomic(path, dumps_waypoints(mission))


def _parse_row(line: str, lineno: int, source: str) -> tuple[int, MissionItem]:
    cells = line.split("\t") if "\t" in line else line.split()
    if len(cells) != len(FIELDS):
        raise InputError(
            f"expected {len(FIELDS)} tab-separated fields, got {len(cells)}",
            file=source,
            row=lineno,
        )
    values: dict[str, float] = {}
    for name, cell in zip(FIELDS, cells, strict=True):
        try:
            values[name] = float(cell)
        except ValueError as exc:
            raise InputError(
                f"not a number: {cell!r}", file=source, row=lineno, field=name
            ) from exc
        if not math.isfinite(values[name]) and name not in ("param1", "param2", "param3", "param4"):
            raise InputError(f"must be finite: {cell!r}", file=source, row=lineno, field=name)
    for name in ("index", "current", "frame", "command", "autocontinue"):
        if values[name] != int(values[name]):
            raise InputError("must be an integer", file=source, row=lineno, field=name)
    frame = int(values["frame"])
    scale = 1e7 if frame in GLOBAL_FRAMES else 1.0
    item = MissionItem(
        seq=0,
        frame=frame,
        command=int(values["command"]),
        current=int(values["current"]),
        autocontinue=int(values["autocontinue"]),
        param1=values["param1"],
        param2=values["param2"],
        param3=values["param3"],
        param4=values["param4"],
        x=int(round(values["lat"] * scale)),
        y=int(round(values["lon"] * scale)),
        z=values["alt"],
    )
    return int(values["index"]), item


def loads_waypoints(text: str, firmware: str = DEFAULT_AUTOPILOT, source: str = "") -> MissionFile:
    """Parse a .waypoints text. ``firmware`` says how to number the items (the format does not
    record it): ArduPilot keeps row 0 as home at seq 0, PX4 starts at row 1."""
    if firmware not in FIRMWARES:
        raise InputError(f"unknown firmware {firmware!r}", field="firmware")
    lines = text.splitlines()
    if not lines or lines[0].strip() != HEADER:
        raise InputError(f"the first line must be {HEADER!r}", file=source, row=1)
    rows: list[MissionItem] = []
    for lineno, line in enumerate(lines[1:], start=2):
        if not line.strip() or line.startswith("#"):
            continue
        index, item = _parse_row(line, lineno, source)
        if index != len(rows):
            raise InputError(
                f"index {index} out of order (expected {len(rows)})",
                file=source,
                row=lineno,
                field="index",
            )
        rows.append(item)
    if not rows:
        raise InputError("no home row", file=source, row=2)
    home_row = rows[0]
    home = (home_row.lat, home_row.lon, home_row.z)
    # Row 0's CURRENT 1 is Mission Planner's mark of the home row, not a state of the item.
    kept = [replace(home_row, current=0), *rows[1:]] if keeps_home_item(firmware) else rows[1:]
    items = tuple(item.with_seq(k) for k, item in enumerate(kept))
    return MissionFile(items=items, firmware=firmware, home=home)


def read_waypoints(path: str | os.PathLike[str], firmware: str = DEFAULT_AUTOPILOT) -> MissionFile:
    """Read a Mission Planner .waypoints file."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read: {exc}", file=str(path)) from exc
    return loads_waypoints(text, firmware, str(path))
