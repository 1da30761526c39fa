"""The mission as ArduPilot serves it by MAVLink FTP: ``@MISSION/mission.dat``.

The file (libraries/AP_Filesystem/AP_Filesystem_Mission.h, ``struct header``, and
AP_Filesystem_Mission.cpp, ``read`` and ``finish_upload``): a 10-byte header of five
little-endian u16 (magic 0x763d, data_type MAV_MISSION_TYPE_*, options, start, num_items),
then ``num_items`` items, each the 38-byte payload of MISSION_ITEM_INT in its wire order. A
read gives item 0 as ArduPilot's home; a write of the whole file (start 0, options 0) clears
the mission and stores the items when the session is closed, and that close fails (a NAK)
when the header's count and the items do not agree, an item is all zeros, or one is refused.

A read does not give back the bytes written: ArduPilot builds the file from the mission it
stores (AP_Mission::get_item, mission_cmd_to_mavlink_int), so :func:`as_stored` is the item as
that file shows it, and :func:`stored_file` the whole file a vehicle holding ``items`` serves.
MAVFTP's CalcFileCRC32 on the file (GCS_FTP::Session::handle_request, AP_Filesystem::crc32) is
:func:`crc32` over that file.
"""

from __future__ import annotations

import math
import struct
import zlib
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from gcs_planner.errors import LinkError
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

MISSION_PATH = "@MISSION/mission.dat"
MAGIC = 0x763D
HEADER = struct.Struct("<HHHHH")
# MISSION_ITEM_INT's payload in wire order: param1-4, x, y, z, seq, command, target system and
# component, frame, current, autocontinue, mission_type.
ITEM = struct.Struct("<ffffiifHHBBBBBB")
MAX_ITEMS = 0xFFFF
# Commands whose position AP_Mission stores as a Location (AP_Mission::stored_in_location):
# their altitude is kept in whole centimetres and their frame as a relative-altitude flag.
LOCATION_COMMANDS = frozenset({16, 17, 18, 19, 21, 22, 30, 31, 82, 84, 85, 92, 94, 179, 189, 191,
                               201})  # fmt: skip
MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_FRAME_GLOBAL_TERRAIN_ALT = 0, 3, 10
_RELATIVE_FRAMES = (3, 6)  # GLOBAL_RELATIVE_ALT and its _INT twin
_TERRAIN_FRAMES = (10, 11)
_MASK = 0xFFFFFFFF


def _pack_item(it: MissionItem, seq: int, target: tuple[int, int] = (0, 0)) -> bytes:
    return ITEM.pack(it.param1, it.param2, it.param3, it.param4, int(it.x), int(it.y),
                     float(it.z), seq, it.command, target[0], target[1], it.frame, it.current,
                     it.autocontinue, MAV_MISSION_TYPE_MISSION)  # fmt: skip


def encode_mission(items: Sequence[MissionItem]) -> bytes:
    """``items`` as mission.dat (a whole-mission write: start 0, no options)."""
    if len(items) > MAX_ITEMS - 1:
        raise LinkError(f"mission.dat holds at most {MAX_ITEMS - 1} items, not {len(items)}")
    out = bytearray(HEADER.pack(MAGIC, MAV_MISSION_TYPE_MISSION, 0, 0, len(items)))
    for seq, it in enumerate(items):
        out += _pack_item(it, seq)
    return bytes(out)


def crc32(data: bytes, crc: int = 0) -> int:
    """ArduPilot's ``crc_crc32`` (AP_Math/crc.cpp): the reflected CRC-32 table of polynomial
    0xEDB88320, from ``crc`` (AP_Filesystem::crc32 starts at 0), with no final inversion. zlib
    inverts on the way in and out, so it is zlib's CRC from the inverted start, inverted."""
    return zlib.crc32(data, crc ^ _MASK) ^ _MASK


def stored_altitude(z: float) -> float:
    """An altitude as ArduPilot gives it back: ``alt = packet.z * 100.0f`` into an integer
    (centimetres, truncated; mavlink_int_to_mission_cmd), then ``alt * 0.01f``
    (mission_cmd_to_mavlink_int), in float32 as the autopilot computes."""
    cm = int(np.float32(z) * np.float32(100.0))
    return float(np.float32(np.float32(cm) * np.float32(0.01)))


def as_stored(item: MissionItem, seq: int, current_nav: int | None = None) -> MissionItem:
    """``item`` as ArduPilot's mission.dat shows it once stored (AP_Mission::get_item and
    mission_cmd_to_mavlink_int): seq its index, autocontinue 1, ``current`` 1 only where the
    command's id equals the running nav command's index (get_item compares ``cmd.id`` with
    it), the frame 0 for commands without a position, and for those with one GLOBAL,
    GLOBAL_RELATIVE_ALT or GLOBAL_TERRAIN_ALT (the _INT frames are stored as the same flags)
    and the altitude through whole centimetres. The parameters are kept as sent: the commands
    that ArduPilot stores narrower (a plane's waypoint keeps acceptance and pass radius in a
    byte each and drops its delay) are not modelled, so a file holding them does not match
    the prediction, and the read-back decides."""
    frame = MAV_FRAME_GLOBAL
    z = float(item.z)
    if item.command in LOCATION_COMMANDS and math.isfinite(z):
        if item.frame in _TERRAIN_FRAMES:
            frame = MAV_FRAME_GLOBAL_TERRAIN_ALT
        elif item.frame in _RELATIVE_FRAMES:
            frame = MAV_FRAME_GLOBAL_RELATIVE_ALT
        z = stored_altitude(z)
    current = int(current_nav is not None and item.command == current_nav)
    return replace(item, seq=seq, frame=frame, z=z, current=current, autocontinue=1)


# AP_Mission::get_item writes these placeholders into every item it gives out.
STORED_TARGET = (1, 1)
# Which of x, y, z mission_cmd_to_mavlink_int writes for a command: a stored Location all three,
# a few commands some (DIGICAM_CONFIGURE, DIGICAM_CONTROL, GIMBAL_MANAGER_PITCHYAW,
# NAV_SCRIPT_TIME, NAV_ATTITUDE_TIME), any other none. What it does not write keeps what the
# item buffer held (see :func:`read_call`).
_XYZ_WRITTEN = {202: "xyz", 203: "xy", 1000: "xz", 42702: "xy", 42703: "x"}
_XYZ_SLICES = {"x": slice(16, 20), "y": slice(20, 24), "z": slice(24, 28)}
CRC_READ = 64  # AP_Filesystem::crc32 reads the file 64 bytes at a time


def xyz_written(command: int) -> str:
    """The fields of x, y, z that ArduPilot's get_item writes for ``command``."""
    return "xyz" if command in LOCATION_COMMANDS else _XYZ_WRITTEN.get(command, "")


def stored_item_bytes(item: MissionItem, seq: int, current_nav: int | None = None) -> bytes:
    """The 38 bytes of ``item`` in ArduPilot's mission.dat (see :func:`as_stored`)."""
    return _pack_item(as_stored(item, seq, current_nav), seq, STORED_TARGET)


def read_call(header: bytes, items: Sequence[tuple[bytes, str]], offset: int, size: int) -> bytes:
    """What one ``read`` of ``size`` bytes at ``offset`` gives (AP_Filesystem_Mission::read):
    ``header``'s bytes, then the items it reaches, each built by get_item into one item
    buffer zeroed at the start of the call, so the x, y, z a command does not write
    (``items``: each item's 38 bytes and the fields written) are the previous item's in that
    call, or 0 for the first. The bytes of such an item therefore depend on where the read
    that built it started: a 64-byte CRC read and a 239-byte burst packet can differ there."""
    out = bytearray(header[offset : offset + size])
    pos = offset + len(out)
    buf = bytearray(ITEM.size)
    end = offset + size
    while pos < end:
        k, within = divmod(pos - len(header), ITEM.size)
        if k >= len(items):
            break
        raw, written = items[k]
        built = bytearray(raw)
        for field, where in _XYZ_SLICES.items():
            if field not in written:
                built[where] = buf[where]
        buf = built
        take = min(ITEM.size - within, end - pos)
        out += built[within : within + take]
        pos += take
    return bytes(out)


def read_whole(header: bytes, items: Sequence[tuple[bytes, str]], chunk: int) -> bytes:
    """The file as read from its start in ``chunk``-byte calls (the CRC's: :data:`CRC_READ`)."""
    out = bytearray()
    while piece := read_call(header, items, len(out), chunk):
        out += piece
    return bytes(out)


def stored_file(items: Sequence[MissionItem], home: bytes, chunk: int = CRC_READ) -> bytes:
    """The mission.dat a vehicle holding ``items`` serves, read in ``chunk``-byte calls: the
    header, ``home`` (item 0's 38 bytes as the vehicle gave them: ArduPilot serves its own
    home there, whatever was sent; a home is a Location, all of it written), then the other
    items as stored."""
    if len(home) != ITEM.size:
        raise ValueError(f"home is {ITEM.size} bytes, not {len(home)}")
    header = HEADER.pack(MAGIC, MAV_MISSION_TYPE_MISSION, 0, 0, len(items))
    rendered = [(home, "xyz")] if items else []
    rendered += [(stored_item_bytes(it, k), xyz_written(it.command))
                 for k, it in enumerate(items[1:], start=1)]  # fmt: skip
    return read_whole(header, rendered, chunk)


def without_leftovers(items: Sequence[MissionItem]) -> list[MissionItem]:
    """``items`` read from ArduPilot's mission.dat with the x, y, z its get_item did not write
    set to 0: those are what the item buffer held from the item before (:func:`read_call`),
    not anything the vehicle stores (the mission protocol gives 0 there)."""
    out = []
    for it in items:
        written = xyz_written(it.command)
        if written == "xyz":
            out.append(it)
            continue
        out.append(replace(it, x=it.x if "x" in written else 0, y=it.y if "y" in written else 0,
                           z=it.z if "z" in written else 0.0))  # fmt: skip
    return out


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


# Where ``current`` lies in an item's 38 bytes (after param1-4, x, y, z, seq, command, target
# system and component, frame).
_CURRENT_AT = struct.calcsize("<ffffiifHHBBB")


def file_crcs(data: bytes) -> list[int]:
    """The CRC-32s a vehicle that served ``data`` (mission.dat as a read gave it) computes of
    its file by CalcFileCRC32: first that of the same file; then, for a vehicle flying it, that
    of the file once its running nav command changed, the one thing a flight changes in it
    (get_item sets ``current`` on every item whose command id equals that index:
    :func:`as_stored`), for each index the mission's commands can match, and for none.

    The file is rebuilt as AP_Filesystem::crc32 reads it, :data:`CRC_READ` bytes a call
    (:func:`read_call`): an item whose command writes no x, y or z carries there what that
    call's buffer held, which a burst read's 239-byte calls need not match."""
    length = mission_length(data)
    if length is None or len(data) != length:
        return [crc32(data)]
    header = data[: HEADER.size]
    raws = [data[HEADER.size + k * ITEM.size : HEADER.size + (k + 1) * ITEM.size]
            for k in range((len(data) - HEADER.size) // ITEM.size)]  # fmt: skip
    commands = [ITEM.unpack_from(raw)[8] for raw in raws]
    # Home (item 0) is a Location: all of its x, y, z are written.
    rendered = [(raw, "xyz" if k == 0 else xyz_written(cmd))
                for k, (raw, cmd) in enumerate(zip(raws, commands, strict=True))]  # fmt: skip
    served = bytearray(read_whole(header, rendered, CRC_READ))
    out = [crc32(bytes(served))]
    for nav in (None, *sorted(set(commands))):
        for k, cmd in enumerate(commands):
            served[HEADER.size + k * ITEM.size + _CURRENT_AT] = int(cmd == nav)
        out.append(crc32(bytes(served)))
    return out
