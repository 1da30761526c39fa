"""QGroundControl ``.plan`` files (JSON): writer and reader.

Layout as QGroundControl saves and loads it: ``fileType`` "Plan", ``version`` 1, a ``mission``
section (version 2) with ``firmwareType`` (MAV_AUTOPILOT), ``vehicleType`` (MAV_TYPE),
``cruiseSpeed``, ``hoverSpeed``, ``plannedHomePosition`` [lat, lon, alt AMSL] and ``items``, and
``geoFence`` and ``rallyPoints`` sections (version 2) that are present even when empty.

Home is not an item of a .plan: it is ``plannedHomePosition``, and a ground station uploading to
ArduPilot puts it back at seq 0. So an ArduPilot mission's seq 0 is left out of ``items`` here and
rebuilt on reading. ``doJumpId`` follows QGroundControl's numbering, in which home is 0 and the
first item 1, for both firmwares.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from pymavlink.dialects.v20 import common

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.aircraft.profile import AUTOPILOT_IDS
from gcs_planner.errors import InputError
from gcs_planner.mission.builder import HOVER_SPEED, Mission
from gcs_planner.mission.items import (
    GLOBAL_FRAMES,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    MissionFile,
    MissionItem,
)
from gcs_planner.runtime.atomic import write_atomic

MAV_AUTOPILOT = AUTOPILOT_IDS
MAV_TYPE_FIXED_WING = common.MAV_TYPE_FIXED_WING
# QGroundControl's AltMode enum (QGroundControlQmlGlobal.h).
QGC_ALT_MODE_RELATIVE = 1
QGC_ALT_MODE_ABSOLUTE = 2
GROUND_STATION = "gcs-planner"


def _coordinate(value: int, frame: int) -> float:
    """A MISSION_ITEM_INT x/y as the .plan writes it: degrees for global frames."""
    return value / 1e7 if frame in GLOBAL_FRAMES else float(value)


def _simple_item(item: MissionItem, jump_id: int) -> dict[str, Any]:
    params = [
        item.param1,
        item.param2,
        item.param3,
        item.param4,
        _coordinate(item.x, item.frame),
        _coordinate(item.y, item.frame),
        item.z,
    ]
    out: dict[str, Any] = {
        "autoContinue": bool(item.autocontinue),
        "command": item.command,
        "doJumpId": jump_id,
        "frame": item.frame,
        # JSON has no NaN; QGroundControl writes an unset parameter as null.
        "params": [None if math.isnan(p) else p for p in params],
        "type": "SimpleItem",
    }
    if item.frame in GLOBAL_FRAMES:
        relative = item.frame in (MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
        out["AMSLAltAboveTerrain"] = None
        out["Altitude"] = item.z
        out["AltitudeMode"] = QGC_ALT_MODE_RELATIVE if relative else QGC_ALT_MODE_ABSOLUTE
    return out


def plan_document(mission: Mission) -> dict[str, Any]:
    """The .plan as a JSON-ready dict."""
    items = mission.items[1:] if keeps_home_item(mission.firmware) else mission.items
    lat, lon, alt = mission.home
    return {
        "fileType": "Plan",
        "version": 1,
        "groundStation": GROUND_STATION,
        "mission": {
            "version": 2,
            "firmwareType": MAV_AUTOPILOT[mission.firmware],
            "vehicleType": MAV_TYPE_FIXED_WING,
            "cruiseSpeed": mission.cruise_speed,
            "hoverSpeed": HOVER_SPEED,
            "plannedHomePosition": [lat, lon, alt],
            "items": [_simple_item(it, k + 1) for k, it in enumerate(items)],
        },
        "geoFence": {"version": 2, "circles": [], "polygons": []},
        "rallyPoints": {"version": 2, "points": []},
    }


def dumps_plan(mission: Mission) -> str:
    return json.dumps(plan_document(mission), indent=4, allow_nan=False) + "\n"


def write_plan(mission: Mission, path: str | os.PathLike[str]) -> Path:
    """Write the mission as a QGroundControl .plan, atomically."""
    return write_atomic(path, dumps_plan(mission))


# ---------------------------------------------------------------------------------------------
# Reading


def _number(value: Any, source: str, row: int | None, field: str) -> float:
    if value is None:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"expected a number, got {value!r}", file=source, row=row, field=field)
    return float(value)


def _integer(value: Any, source: str, row: int | None, field: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(f"expected an integer, got {value!r}", file=source, row=row, field=field)
    return value


def _read_item(raw: Any, seq: int, source: str, row: int) -> MissionItem:
    if not isinstance(raw, dict) or raw.get("type") != "SimpleItem":
        kind = raw.get("type") if isinstance(raw, dict) else type(raw).__name__
        raise InputError(f"only SimpleItem is supported, got {kind!r}", file=source, row=row)
    params = raw.get("params")
    if not isinstance(params, list) or len(params) != 7:
        raise InputError("'params' must be a list of 7", file=source, row=row, field="params")
    frame = _integer(raw.get("frame"), source, row, "frame")
    p = [_number(v, source, row, "params") for v in params]

    def coord(v: float) -> int:
        if math.isnan(v):
            return 0
        return int(round(v * 1e7)) if frame in GLOBAL_FRAMES else int(round(v))

    return MissionItem(
        seq=seq,
        frame=frame,
        command=_integer(raw.get("command"), source, row, "command"),
        autocontinue=1 if raw.get("autoContinue", True) else 0,
        param1=p[0],
        param2=p[1],
        param3=p[2],
        param4=p[3],
        x=coord(p[4]),
        y=coord(p[5]),
        z=p[6],
    )


def loads_plan(text: str, source: str = "") -> MissionFile:
    """Parse a .plan. Items come back as the firmware stores them (ArduPilot: home at seq 0)."""
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"not JSON: {exc.msg}", file=source, row=exc.lineno) from exc
    if not isinstance(doc, dict) or doc.get("fileType") != "Plan":
        raise InputError("not a QGroundControl plan (fileType)", file=source, field="fileType")
    if doc.get("version") != 1:
        raise InputError("unsupported .plan version", file=source, field="version")
    mission = doc.get("mission")
    if not isinstance(mission, dict) or mission.get("version") != 2:
        raise InputError("unsupported mission section", file=source, field="mission")
    firmware = {v: k for k, v in MAV_AUTOPILOT.items()}.get(mission.get("firmwareType"))
    if firmware is None:
        raise InputError(
            f"firmwareType {mission.get('firmwareType')!r} is neither ArduPilot (3) nor PX4 (12)",
            file=source,
            field="firmwareType",
        )
    home_raw = mission.get("plannedHomePosition")
    if not isinstance(home_raw, list) or len(home_raw) != 3:
        raise InputError("expected [lat, lon, alt]", file=source, field="plannedHomePosition")
    home = tuple(_number(v, source, None, "plannedHomePosition") for v in home_raw)
    raw_items = mission.get("items")
    if not isinstance(raw_items, list):
        raise InputError("'items' must be a list", file=source, field="items")
    items: list[MissionItem] = []
    if keeps_home_item(firmware):
        items.append(
            MissionItem(
                seq=0,
                frame=MAV_FRAME_GLOBAL,
                command=MAV_CMD_NAV_WAYPOINT,
                x=int(round(home[0] * 1e7)),
                y=int(round(home[1] * 1e7)),
                z=home[2],
                note="home",
            )
        )
    for row, raw in enumerate(raw_items):
        items.append(_read_item(raw, len(items), source, row))
    speed = mission.get("cruiseSpeed")
    return MissionFile(
        items=tuple(items),
        firmware=firmware,
        home=(home[0], home[1], home[2]),
        cruise_speed=None if speed is None else _number(speed, source, None, "cruiseSpeed"),
    )


def read_plan(path: str | os.PathLike[str]) -> MissionFile:
    """Read a QGroundControl .plan file."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read: {exc}", file=str(path)) from exc
    return loads_plan(text, str(path))
