"""Missions by MAVFTP: whether to send them so, and the upload, read, read-back and CRC check of
``@MISSION/mission.dat``.

``transfer="auto"`` uses the file when the vehicle's AUTOPILOT_VERSION sets
MAV_PROTOCOL_CAPABILITY_FTP and its autopilot serves the mission as a file (the record's
``protocol.serves_mission_file``: ArduPilot's AP_Filesystem_Mission; PX4 sets the bit for its
file system only), and falls back to the mission protocol when the vehicle answers that it has
no such file, or keeps the file busy (another ground station's upload holds it).

The CRC check: ArduPilot builds the file it serves from the mission it stores
(AP_Filesystem_Mission::read through AP_Mission::get_item), not from the bytes it was sent, so
a CRC-32 equal to that of the file predicted for the items sent
(:func:`~gcs_planner.link.mission_ftp.stored_file`, with the vehicle's own home read from the
file's first item) says it stores them, every byte. A download is checked the same way: the
CRC the vehicle computes of its file against the CRC of the file as read
(:func:`read_file_checked`).
"""

from __future__ import annotations

from collections.abc import Sequence

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.errors import LinkError, UploadRefused
from gcs_planner.link.connection import mavlink
from gcs_planner.link.ftp import (
    FILE_NOT_FOUND,
    NAK,
    UNKNOWN_COMMAND,
    FtpBusy,
    FtpClient,
    FtpError,
    FtpQuiet,
)
from gcs_planner.link.mission_ftp import (
    HEADER,
    ITEM,
    MAGIC,
    MISSION_PATH,
    crc32,
    decode_mission,
    encode_mission,
    file_crcs,
    mission_length,
    stored_file,
    stored_item_bytes,
    without_leftovers,
)
from gcs_planner.link.outcome import ACKNOWLEDGED, Outcome, ReadBackError, unconfirmed
from gcs_planner.link.session import VehicleSession, serves_mission_file
from gcs_planner.mission.items import MissionItem

# An open refused with these says the vehicle has no such file or no FTP: auto falls back.
_NO_MISSION_FILE = (FILE_NOT_FOUND, UNKNOWN_COMMAND)


def use_ftp(session: VehicleSession) -> bool:
    """Whether the session's missions go by MAVFTP: as chosen, or for ``auto`` when the
    vehicle's autopilot serves the mission file and announces MAVFTP."""
    if session.transfer == "mission":
        return False
    if session.transfer == "ftp":
        return True
    # Any other autopilot is not asked for its capabilities at all.
    if not serves_mission_file(session.firmware):
        return False
    return bool(session.autopilot_capabilities() & mavlink.MAV_PROTOCOL_CAPABILITY_FTP)


def ftp_client(session: VehicleSession) -> FtpClient:
    """An FTP client that talks to the session's vehicle, paced by its radio."""
    return FtpClient(
        session.mav,
        session.link.send,
        lambda t: session._recv(t, {"FILE_TRANSFER_PROTOCOL"}, None),
        session._target(),
        timeout=session.timeout,
        retries=session.retries,
        extra_wait=session.radio.extra_wait,
        congested=session.radio.congested,
        radio_reports=lambda: session.radio.present,
        hint=session.signing_hint,
    )


def falls_back(session: VehicleSession, exc: FtpError) -> bool:
    """Whether an FTP failure sends an automatic choice back to the mission protocol: the
    vehicle has no mission file (or no FTP) at all; its file stayed busy through every
    reset and wait (the mission protocol does not share AP_Filesystem_Mission's one
    upload at a time); or one FTP request went unanswered through all its resends, which
    at 30 % loss each way befalls about one exchange in 60 (0.51 ** 6), where the mission
    protocol resends at the round trip's pace until nothing has come for its stall limit.
    Nothing an upload failing so sent was stored: the vehicle stores the file when it is
    closed, and a close whose answer was lost is not an FtpError (an UNCONFIRMED outcome)."""
    if session.transfer != "auto":
        return False
    return exc.code in _NO_MISSION_FILE or isinstance(exc, (FtpBusy, FtpQuiet))


def upload_file(session: VehicleSession, items: Sequence[MissionItem]) -> Outcome:
    """Write ``items`` as the vehicle's mission file; :class:`UploadRefused` when the vehicle
    did not store it."""
    data = encode_mission(items)
    client = ftp_client(session)
    try:
        client.reset()
        reply = client.write(MISSION_PATH, data)
    finally:
        session.retry_count += client.retry_count
    if reply is None:
        return unconfirmed(f"no answer came to the close of {MISSION_PATH}")
    if reply.opcode == NAK:
        raise UploadRefused(
            f"upload refused: the vehicle did not store {MISSION_PATH} when it was closed "
            f"(TerminateSession NAK: {reply.nak_text()}); ArduPilot refuses the whole file "
            "when its header's count and the items disagree or an item is one it does not "
            "store, and keeps the mission it had"
        )
    return ACKNOWLEDGED


def read_file(session: VehicleSession, chunks: dict[int, bytes]) -> list[MissionItem]:
    """The vehicle's mission, read from its file into ``chunks`` (resumed from what is there)."""
    client = ftp_client(session)
    try:
        data = client.read(MISSION_PATH, mission_length, chunks)
    finally:
        session.retry_count += client.retry_count
    return _items(data)


def _items(data: bytes) -> list[MissionItem]:
    # A command without a position carries in ArduPilot's file the x, y, z of the item read
    # before it (one item buffer per read call), which the vehicle does not store.
    return without_leftovers(decode_mission(data))


def read_file_checked(session: VehicleSession) -> tuple[list[MissionItem], str]:
    """The vehicle's mission read from its file, and "" when the vehicle's CalcFileCRC32 of the
    file is that of the bytes read; else why no CRC could be had (the vehicle refused it or
    did not answer), for the caller to check the mission another way. A CRC that differs is a
    :class:`LinkError`: a byte was altered on the way (each frame's own checksum is 16 bits,
    and a relay that rewrites a frame writes a good one), or the mission changed meanwhile."""
    client = ftp_client(session)
    try:
        data = client.read(MISSION_PATH, mission_length, {})
        items = _items(data)
        try:
            vehicle_crc = client.crc32(MISSION_PATH)
        except FtpError as exc:
            return items, f"no CRC: {exc}"
    finally:
        session.retry_count += client.retry_count
    expected = file_crcs(data)
    if vehicle_crc not in expected:
        raise LinkError(
            f"the mission file read by MAVFTP is not the vehicle's: its CRC-32 is "
            f"0x{expected[0]:08x}, the vehicle's 0x{vehicle_crc:08x}. It was altered on the "
            "way, or the mission changed meanwhile: download it again"
        )
    return items, ""


def read_back_file(
    session: VehicleSession, *, acknowledged: bool, attempts: int = 3
) -> list[MissionItem]:
    """The read-back by MAVFTP: as the mission protocol's, resuming across attempts from the
    bytes already read; a read-back that fails is a :class:`ReadBackError`."""
    chunks: dict[int, bytes] = {}
    for attempt in range(attempts):
        try:
            return read_file(session, chunks)
        except LinkError as exc:
            if attempt < attempts - 1:
                continue
            said = (
                "the vehicle acknowledged the close of the mission file"
                if acknowledged
                else "the vehicle never acknowledged the close of the mission file"
            )
            held = sum(len(c) for c in chunks.values())
            raise ReadBackError(
                f"{said} but it could not be read back to verify it: {exc}. {held} bytes "
                "were read back; the read-back failed, so whether the vehicle holds this "
                "mission is unknown: run `gcs-planner download` to check"
            ) from None
    raise AssertionError("unreachable")


def crc_check(session: VehicleSession, sent: Sequence[MissionItem]) -> str:
    """Empty when the vehicle's CRC of its mission file is that of the file it serves holding
    ``sent``; otherwise why not (the read-back then decides). Item 0 of that file is the
    vehicle's own home, so its first 48 bytes are read to predict the file; a home that moves
    between the two answers only costs the read-back."""
    if not sent:
        return "nothing was sent"
    client = ftp_client(session)
    try:
        head = client.read_head(MISSION_PATH, HEADER.size + ITEM.size)
        vehicle_crc = client.crc32(MISSION_PATH)
    except FtpError as exc:
        return f"no CRC: {exc}"
    finally:
        session.retry_count += client.retry_count
    if len(head) < HEADER.size + ITEM.size:
        return f"the file's first {len(head)} bytes hold no home item"
    magic, _, _, _, count = HEADER.unpack_from(head)
    if magic != MAGIC or count != len(sent):
        return f"the file's header says {count} items (magic 0x{magic:04x})"
    # An autopilot that keeps home at item 0 serves its own home there (the read-back skips it
    # likewise); any other is held to the item sent.
    if keeps_home_item(session.firmware):
        home = head[HEADER.size :]
    else:
        home = stored_item_bytes(sent[0], 0)
    expected = crc32(stored_file(sent, home))
    if vehicle_crc != expected:
        return f"CRC 0x{vehicle_crc:08x}, expected 0x{expected:08x}"
    return ""
