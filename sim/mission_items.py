"""The mission items each autopilot takes and how they cross the wire: the commands it stores
(by its record's ``protocol.commands_by_frame``), the range checks an item passes before it is
stored (:func:`check_item`), and the legacy float MISSION_ITEM read and written
(:mod:`sim.mission_server` serves the protocol that carries them).
"""

from __future__ import annotations

import math
from typing import Any

from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT, MissionProtocol, autopilot_for
from gcs_planner.link.connection import mavlink
from gcs_planner.link.protocol import GLOBAL_FLOAT_FRAMES, GLOBAL_INT_FRAMES
from gcs_planner.mission.items import MISSION_FRAMES, POSITION_COMMANDS, MissionItem

MAV_FRAME_MISSION = 2
# The commands each autopilot takes; the record's ``protocol.commands_by_frame`` says which set
# applies. ArduPilot (AP_Mission, ``mavlink_int_to_mission_cmd``): the commands this mock's
# ArduPlane stores, in any supported frame.
SUPPORTED_COMMANDS = frozenset(
    {16, 17, 18, 19, 20, 21, 22, 31, 112, 113, 114, 115, 176, 177, 178, 179, 183, 184, 189, 201}
)
# PX4 (mavlink_mission.cpp, parse_mavlink_mission_item), by frame. A global frame (0, 3, 5, 6):
# WAYPOINT 16, LOITER_UNLIM 17, LOITER_TIME 19, LAND 21, TAKEOFF 22, LOITER_TO_ALT 31, ROI 80,
# VTOL_TAKEOFF 84, VTOL_LAND 85, DO_SET_ROI_LOCATION 195, DO_SET_ROI 201, AUTOTUNE 212,
# ARM_DISARM 400, CONDITION_GATE 4501, the fence vertices/circles 5001-5004, FENCE_RETURN 5000,
# RALLY_POINT 5100. No LOITER_TURNS (18): PX4 answers it MAV_MISSION_UNSUPPORTED.
PX4_GLOBAL_COMMANDS = frozenset(
    {16, 17, 19, 21, 22, 31, 80, 84, 85, 195, 201, 212, 400, 4501, 5000, 5001, 5002, 5003, 5004,
     5100}
)  # fmt: skip
# Frame MISSION (2): DO_JUMP 177, ROI 80 / DO_SET_ROI 201, WINCH 42600, GRIPPER 211,
# CHANGE_SPEED 178, SET_HOME 179, LAND_START 189, TRIGGER_CONTROL 2003, DIGICAM 203,
# MOUNT 204/205, GIMBAL 1000/1001, camera 530/531/534, IMAGE 2000/2001, VIDEO 2500/2501,
# CONTROL_VIDEO 200, CAM_TRIGG_DIST 206, OBLIQUE_SURVEY 260, CAM_TRIGG_INTERVAL 214,
# VTOL_TRANSITION 3000, NAV_DELAY 93, RTL 20, ROI_WPNEXT_OFFSET 196, ROI_NONE 197,
# CONDITION_DELAY 112, CONDITION_DISTANCE 114, SET_ACTUATOR 187, AUTOTUNE 212, ARM_DISARM 400.
PX4_MISSION_FRAME_COMMANDS = frozenset(
    {20, 80, 93, 112, 114, 177, 178, 179, 187, 189, 196, 197, 200, 201, 203, 204, 205, 206, 211,
     212, 214, 260, 400, 530, 531, 534, 1000, 1001, 2000, 2001, 2003, 2500, 2501, 3000, 42600}
)  # fmt: skip
ALT_RANGE_M = (-1000.0, 100_000.0)
INT32 = (-(2**31), 2**31 - 1)
FLOAT32_MAX = 3.4028234663852886e38

Peer = tuple[int, int]  # (system id, component id)


def fits_int32(value: int) -> bool:
    return INT32[0] <= value <= INT32[1]


def mission_protocol(flavour: str) -> MissionProtocol:
    """How ``flavour``'s mission protocol answers (its record's ``protocol``)."""
    protocol = autopilot_for(flavour).protocol
    if protocol is None:
        raise ValueError(f"the autopilot {flavour!r} has no mission protocol to serve")
    return protocol


def supports(item: MissionItem, flavour: str = DEFAULT_AUTOPILOT) -> bool:
    """Whether ``flavour`` has a mission item for ``item``'s command in its frame."""
    if mission_protocol(flavour).commands_by_frame:
        if item.frame == MAV_FRAME_MISSION:
            return item.command in PX4_MISSION_FRAME_COMMANDS
        return item.command in PX4_GLOBAL_COMMANDS
    return item.command in SUPPORTED_COMMANDS


def check_item(item: MissionItem, flavour: str = DEFAULT_AUTOPILOT) -> int:
    """The MAV_MISSION_RESULT ``flavour`` gives ``item``: ACCEPTED, or why not."""
    if item.frame not in MISSION_FRAMES:
        return mavlink.MAV_MISSION_UNSUPPORTED_FRAME
    if not supports(item, flavour):
        return mavlink.MAV_MISSION_UNSUPPORTED
    if not 0 <= item.autocontinue <= 1:
        return mavlink.MAV_MISSION_INVALID
    if not fits_int32(item.x):
        return mavlink.MAV_MISSION_INVALID_PARAM5_X
    if not fits_int32(item.y):
        return mavlink.MAV_MISSION_INVALID_PARAM6_Y
    if math.isfinite(item.z) and abs(item.z) > FLOAT32_MAX:
        return mavlink.MAV_MISSION_INVALID_PARAM7
    for name, result in (
        ("param1", mavlink.MAV_MISSION_INVALID_PARAM1),
        ("param2", mavlink.MAV_MISSION_INVALID_PARAM2),
        ("param3", mavlink.MAV_MISSION_INVALID_PARAM3),
        ("param4", mavlink.MAV_MISSION_INVALID_PARAM4),
    ):
        value = getattr(item, name)
        if math.isfinite(value) and abs(value) > FLOAT32_MAX:
            return result
    if item.command in POSITION_COMMANDS and item.frame != 2:
        if not -900_000_000 <= item.x <= 900_000_000:
            return mavlink.MAV_MISSION_INVALID_PARAM5_X
        if not -1_800_000_000 <= item.y <= 1_800_000_000:
            return mavlink.MAV_MISSION_INVALID_PARAM6_Y
        if not (math.isfinite(item.z) and ALT_RANGE_M[0] <= item.z <= ALT_RANGE_M[1]):
            return mavlink.MAV_MISSION_INVALID_PARAM7
    return mavlink.MAV_MISSION_ACCEPTED


def item_from_wire(msg: Any) -> MissionItem | int:
    """The item a MISSION_ITEM_INT or legacy MISSION_ITEM carries, or the MAV_MISSION_RESULT
    that refuses it (a legacy float that does not fit the integer the vehicle stores)."""
    x, y = float(msg.x), float(msg.y)
    if msg.get_type() == "MISSION_ITEM":
        scale = 1e7 if msg.frame in GLOBAL_FLOAT_FRAMES or msg.frame in GLOBAL_INT_FRAMES else 1e4
        x, y = x * scale, y * scale
        if not (math.isfinite(x) and fits_int32(round(x))):
            return mavlink.MAV_MISSION_INVALID_PARAM5_X
        if not (math.isfinite(y) and fits_int32(round(y))):
            return mavlink.MAV_MISSION_INVALID_PARAM6_Y
    return MissionItem.from_wire(msg, round(x), round(y))


def legacy_item_message(mav: Any, item: MissionItem, target: Peer) -> Any:
    """MISSION_ITEM (float latitude/longitude in degrees), what autopilots answer a legacy
    MISSION_REQUEST with."""
    global_frame = item.frame in GLOBAL_FLOAT_FRAMES or item.frame in GLOBAL_INT_FRAMES
    scale = 1e7 if global_frame else 1e4
    return mav.mission_item_encode(
        target[0],
        target[1],
        item.seq,
        item.frame,
        item.command,
        item.current,
        item.autocontinue,
        item.param1,
        item.param2,
        item.param3,
        item.param4,
        item.x / scale,
        item.y / scale,
        item.z,
        item.mission_type,
    )
