"""The mission as ArduPilot serves it by MAVLink FTP: ``@MISSION/mission.dat``.

The file (libraries/AP_Filesystem/AP_Filesystem_Mission.h, ``struct header``, and
AP_Filesystem_Mission.cpp, ``read`` and ``finish_upload``): a 10-byte header of five
little-endian u16 (magic 0x763d, data_type MAV_MISSION_TYPE_*, options, start, num_items),
then ``num_items`` items, each the 38-byte payload of MISSION_ITEM_INT in its wire order. A
read gives item 0 as ArduPilot's home; a write of the whole file (start 0, options 0) clears
the mission and stores the items when the session is closed, and that close fails (a NAK)
when the header's count and the items do not agree, an item is all zeros, or one is refused.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

from gcs_planner.errors import LinkError
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

MISSION_PATH = "@MISSION/mission.dat"
MAGIC = 0x763D
HEADER = struct.Struct("<HHHHH")
# MISSION_ITEM_INT's payload in wire order: param1-4, x, y, z, seq, command, target system and
# component, frame, current, autocontinue, mission_type.
ITEM = struct.Struct("<ffffiifHHBBBBBB")
MAX_ITEMS = 0xFFFF


def encode_mission(items: Sequence[MissionItem]) -> bytes:
    """``items`` as mission.dat (a whole-mission write: start 0, no options)."""
    if len(items) > MAX_ITEMS - 1:
        raise LinkError(f"mission.dat holds at most {MAX_ITEMS - 1} items, not {len(items)}")
    out = bytearray(HEADER.pack(MAGIC, MAV_MISSION_TYPE_MISSION, 0, 0, len(items)))
    for seq, it in enumerate(items):
        out += ITEM.pack(it.param1, it.param2, it.param3, it.param4, int(it.x), int(it.y),
                         float(it.z), seq, it.command, 0, 0, it.frame, it.current,
                         it.autocontinue, MAV_MISSION_TYPE_MISSION)  # fmt: skip
    return bytes(out)


def mission_length(prefix: bytes) -> int | None:
    """The file's length from its header (None until the header has been read)."""
    if len(prefix) < HEADER.size:
        return None
    magic, _, _, _, count = HEADER.unpack_from(prefix)
    if magic != MAGIC:
        raise LinkError(
            f"the vehicle's {MISSION_PATH} is not a mission file: magic 0x{magic:04x}, "
            f"expected 0x{MAGIC:04x}"
        )
    return HEADER.size + count * ITEM.size


def decode_mission(data: bytes) -> list[MissionItem]:
    """The items of a mission.dat; anything that is not one is a :class:`LinkError` naming
    the field."""
    length = mission_length(data)
    if length is None:
        raise LinkError(
            f"the vehicle's {MISSION_PATH} is {len(data)} bytes: shorter than its header"
        )
    _, data_type, options, start, count = HEADER.unpack_from(data)
    if data_type != MAV_MISSION_TYPE_MISSION:
        raise LinkError(
            f"the vehicle's {MISSION_PATH}: header field 'data_type' is {data_type}, not "
            f"{MAV_MISSION_TYPE_MISSION} (a mission)"
        )
    if start != 0:
        raise LinkError(f"the vehicle's {MISSION_PATH}: header field 'start' is {start}, not 0")
    if len(data) != length:
        raise LinkError(
            f"the vehicle's {MISSION_PATH} is {len(data)} bytes, but its header's "
            f"{count} items make {length}"
        )
    items = []
    for seq in range(count):
        (p1, p2, p3, p4, x, y, z, _, command, _, _, frame, current, autocontinue,
         _) = ITEM.unpack_from(data, HEADER.size + seq * ITEM.size)  # fmt: skip
        items.append(MissionItem(seq, frame, command, current, autocontinue, p1, p2, p3, p4,
                                 x, y, z))  # fmt: skip
    del options  # NO_CLEAR is for writes; a read has nothing to say there
    return items
