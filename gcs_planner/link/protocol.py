"""The mission protocol's vocabulary: results as sentences, items to and from messages, and
the comparison of an uploaded mission with what the vehicle gives back.

Kept free of any transfer state so that both sides of the protocol and the tests can use it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from gcs_planner.link.connection import mavlink
from gcs_planner.link.mission_ftp import LOCATION_COMMANDS
from gcs_planner.mission.items import MissionItem

# The MAVLink specification's recommended timeout and retries (mission protocol, "Timeouts and
# Retries"); QGroundControl uses the same numbers.
DEFAULT_TIMEOUT_S = 1.5
ITEM_TIMEOUT_S = 0.25
DEFAULT_RETRIES = 5

# Frames whose x/y are latitude/longitude: the _INT variants carry degE7, the others degrees.
GLOBAL_INT_FRAMES = frozenset({5, 6, 11})
GLOBAL_FLOAT_FRAMES = frozenset({0, 3, 10})
# Autopilots store the altitude reference, not whether the GCS sent the _INT spelling, and give
# back either (ArduPilot answers 3 for an item sent as 6): compare frames modulo that.
_SAME_FRAME = {0: 0, 5: 0, 3: 3, 6: 3, 10: 10, 11: 10}
# A command without a position has no frame to keep: ArduPilot stores none and gives such an
# item back with frame 0 (mission_cmd_to_mavlink_int), whether it was sent as 0 or as 2
# (MAV_FRAME_MISSION).
_NO_POSITION_FRAMES = frozenset({0, 2})

RESULT_TEXT = {
    mavlink.MAV_MISSION_ACCEPTED: "accepted",
    mavlink.MAV_MISSION_ERROR: "the vehicle reported a generic mission error",
    mavlink.MAV_MISSION_UNSUPPORTED_FRAME: "the vehicle does not support an item's frame",
    mavlink.MAV_MISSION_UNSUPPORTED: "the vehicle does not support an item's command or this "
    "mission type",
    mavlink.MAV_MISSION_NO_SPACE: "the mission has more items than the vehicle can store",
    mavlink.MAV_MISSION_INVALID: "an item has an invalid parameter",
    mavlink.MAV_MISSION_INVALID_PARAM1: "an item's param1 is invalid",
    mavlink.MAV_MISSION_INVALID_PARAM2: "an item's param2 is invalid",
    mavlink.MAV_MISSION_INVALID_PARAM3: "an item's param3 is invalid",
    mavlink.MAV_MISSION_INVALID_PARAM4: "an item's param4 is invalid",
    mavlink.MAV_MISSION_INVALID_PARAM5_X: "an item's latitude (x) is invalid or out of range",
    mavlink.MAV_MISSION_INVALID_PARAM6_Y: "an item's longitude (y) is invalid or out of range",
    mavlink.MAV_MISSION_INVALID_PARAM7: "an item's altitude (z) is invalid or out of range",
    mavlink.MAV_MISSION_INVALID_SEQUENCE: "an item arrived out of sequence",
    mavlink.MAV_MISSION_DENIED: "the vehicle is not accepting mission commands now (busy with "
    "another ground station's transfer?)",
    mavlink.MAV_MISSION_OPERATION_CANCELLED: "the vehicle cancelled the transfer (it timed out "
    "waiting for items)",
}


def result_name(result: int) -> str:
    enum = mavlink.enums.get("MAV_MISSION_RESULT", {})
    entry = enum.get(result)
    return entry.name if entry is not None else f"MAV_MISSION_RESULT {result}"


def describe_result(result: int) -> str:
    """``MAV_MISSION_NO_SPACE: the mission has more items than the vehicle can store``."""
    text = RESULT_TEXT.get(result, "unknown result code")
    return f"{result_name(result)}: {text}"


def item_to_message(mav: Any, item: MissionItem, target_system: int, target_component: int) -> Any:
    """MISSION_ITEM_INT carrying ``item`` (always the _INT message, as the spec asks)."""
    return mav.mission_item_int_encode(
        target_system,
        target_component,
        item.seq,
        item.frame,
        item.command,
        item.current,
        item.autocontinue,
        item.param1,
        item.param2,
        item.param3,
        item.param4,
        int(item.x),
        int(item.y),
        float(item.z),
        item.mission_type,
    )


def item_from_message(msg: Any) -> MissionItem:
    """A :class:`MissionItem` from MISSION_ITEM_INT, or from the deprecated float MISSION_ITEM
    (whose global latitude/longitude are degrees and become degE7 here)."""
    x, y = msg.x, msg.y
    if msg.get_type() == "MISSION_ITEM":
        if msg.frame in GLOBAL_FLOAT_FRAMES or msg.frame in GLOBAL_INT_FRAMES:
            x = _deg_e7(x)
            y = _deg_e7(y)
        else:
            x, y = _local_e4(x), _local_e4(y)
    return MissionItem.from_wire(msg, x, y)


def _deg_e7(value: float) -> int:
    return round(value * 1e7) if math.isfinite(value) else 2**31 - 1


def _local_e4(value: float) -> int:
    return round(value * 1e4) if math.isfinite(value) else 2**31 - 1


@dataclass(frozen=True)
class Tolerance:
    """How far a read-back item may be from the sent one and still be the same item.

    Latitude/longitude are integers on the wire: at most ``xy`` (degE7) apart, 1 = about 1 cm.
    Altitude: ArduPilot stores centimetres, so ``z`` metres. Params travel as float32 and some
    autopilots store them narrower: relative ``param_rel`` with an absolute floor ``param_abs``.
    """

    xy: int = 1
    z: float = 0.011
    param_rel: float = 1e-6
    param_abs: float = 1e-4


def _param_close(a: float, b: float, tol: Tolerance) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return abs(a - b) <= max(tol.param_abs, tol.param_rel * max(abs(a), abs(b)))


_EXACT = Tolerance()


def item_differences(sent: MissionItem, got: MissionItem, tol: Tolerance = _EXACT) -> list[str]:
    """What differs between a sent item and the one read back, in words (empty when equal)."""
    out: list[str] = []
    if sent.command != got.command:
        out.append(f"command {sent.command} became {got.command}")
    if _SAME_FRAME.get(sent.frame, sent.frame) != _SAME_FRAME.get(got.frame, got.frame) and not (
        {sent.frame, got.frame} <= _NO_POSITION_FRAMES and sent.command not in LOCATION_COMMANDS
    ):
        out.append(f"frame {sent.frame} became {got.frame}")
    if sent.autocontinue != got.autocontinue:
        out.append(f"autocontinue {sent.autocontinue} became {got.autocontinue}")
    for name in ("param1", "param2", "param3", "param4"):
        a, b = getattr(sent, name), getattr(got, name)
        if not _param_close(a, b, tol):
            out.append(f"{name} {a!r} became {b!r}")
    if abs(int(sent.x) - int(got.x)) > tol.xy:
        out.append(f"x {sent.x} became {got.x}")
    if abs(int(sent.y) - int(got.y)) > tol.xy:
        out.append(f"y {sent.y} became {got.y}")
    if not (abs(sent.z - got.z) <= tol.z or (math.isnan(sent.z) and math.isnan(got.z))):
        out.append(f"z {sent.z!r} became {got.z!r}")
    return out


def mission_differences(
    sent: Sequence[MissionItem],
    got: Sequence[MissionItem],
    *,
    skip_home: bool = False,
    tol: Tolerance | None = None,
) -> list[str]:
    """Every difference between the uploaded mission and the read-back one, in words.

    ``skip_home``: ArduPilot keeps its own home in item 0 whatever was sent there, so that item
    is only required to exist.
    """
    tol = tol or Tolerance()
    out: list[str] = []
    if skip_home and not sent and len(got) == 1:
        return out  # an empty ArduPilot mission is its home alone
    if len(sent) != len(got):
        out.append(f"the vehicle holds {len(got)} items, {len(sent)} were uploaded")
    for i, (a, b) in enumerate(zip(sent, got, strict=False)):
        if b.seq != i:
            out.append(f"item {i}: read back with seq {b.seq}")
        if skip_home and i == 0:
            continue
        for diff in item_differences(a, b, tol):
            out.append(f"item {i}: {diff}")
    return out
