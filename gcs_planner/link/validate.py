"""Is a mission item one this planner may send or write? One rule set for both directions.

An item read from a file is checked before anything is sent (MISSION_ITEM_INT packs latitude
and longitude as int32 degE7, so a latitude typed in degE7 would not even pack), and an item
downloaded from a vehicle is checked before anything is written (a file is only as good as the
vehicle that filled it). The checks follow MAVLink's MISSION_ITEM_INT definition
(common.xml): x/y are PARAM5/PARAM6, latitude/longitude in degE7 for global frames; "NaN or
INT32_MAX may be used in float/integer params (respectively) to indicate optional/default
values". NaN params therefore pass; an INT32_MAX position is "not set", which a .waypoints or
JSON file of ours cannot say, so a position item without a position is refused.

Latitude, longitude and altitude are only positions for the commands that fly to a place; for
the others (DO_CHANGE_SPEED, ...) x/y/z are plain parameters, as ArduPilot and PX4 treat them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcs_planner.link.connection import mavlink
from gcs_planner.mission.items import (
    GLOBAL_FRAMES,
    MISSION_FRAMES,
    POSITION_COMMANDS,
    MissionItem,
)

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1
FLOAT32_MAX = 3.4028234663852886e38
# Below the shore of the Dead Sea is below any runway; above 100 km is space.
ALTITUDE_RANGE_M = (-1000.0, 100_000.0)
KNOWN_COMMANDS = frozenset(
    value
    for value, entry in mavlink.enums.get("MAV_CMD", {}).items()
    if not entry.name.endswith("_ENUM_END")
)


@dataclass(frozen=True)
class ItemProblem:
    """What is wrong with an item: ``field`` as a .waypoints column names it."""

    field: str
    reason: str


def _enum_name(enum: str, value: int) -> str | None:
    entry = mavlink.enums.get(enum, {}).get(value)
    return None if entry is None or entry.name.endswith("_ENUM_END") else entry.name


def _float32_ok(value: float) -> bool:
    return math.isnan(value) or (math.isfinite(value) and abs(value) <= FLOAT32_MAX)


def item_problem(item: MissionItem) -> ItemProblem | None:
    """The first thing wrong with ``item``, or None when it may be sent and written."""
    if item.frame not in MISSION_FRAMES:
        name = _enum_name("MAV_FRAME", item.frame)
        what = f"({name}) is not one this planner's missions use" if name else "is not a MAV_FRAME"
        return ItemProblem("frame", f"frame {item.frame} {what}: expected 0, 2, 3, 5 or 6")
    if item.command not in KNOWN_COMMANDS:
        return ItemProblem("command", f"command {item.command} is not a MAVLink MAV_CMD")
    for name in ("current", "autocontinue"):
        if getattr(item, name) not in (0, 1):
            return ItemProblem(name, f"{name} {getattr(item, name)} is not 0 or 1")
    for name in ("param1", "param2", "param3", "param4"):
        value = getattr(item, name)
        if not _float32_ok(value):
            return ItemProblem(name, f"{value!r} is neither a float32 number nor NaN (unset)")
    position = item.command in POSITION_COMMANDS and item.frame in GLOBAL_FRAMES
    for name, value, limit, plane in (("lat", item.x, 90, "x"), ("lon", item.y, 180, "y")):
        if position and value == INT32_MAX:
            return ItemProblem(
                name,
                f"{name} is not set (INT32_MAX, MAVLink's 'unset' value): a position item "
                "needs a position in a mission file",
            )
        if position and abs(value) > limit * 10**7:
            return ItemProblem(
                name, f"{name} {value / 1e7:.7f}° is beyond ±{limit}° (a value in degE7?)"
            )
        if not INT32_MIN <= value <= INT32_MAX:
            return ItemProblem(
                name, f"{plane} {value} does not fit MISSION_ITEM_INT's int32 {plane}"
            )
    if not math.isfinite(item.z) or abs(item.z) > FLOAT32_MAX:
        return ItemProblem("alt", f"{item.z!r} is not a finite float32 number")
    low, high = ALTITUDE_RANGE_M
    if position and not low <= item.z <= high:
        return ItemProblem("alt", f"altitude {item.z:g} m is outside {low:g}..{high:g} m")
    return None
