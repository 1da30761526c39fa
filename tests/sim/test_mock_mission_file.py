"""The mock's ArduPilot as ArduPilot gives its mission back and bounds its mission file: the
same items by the mission protocol and by MAVFTP (both are ``AP_Mission::get_item``), and a
WriteFile past the room it has refused as ``AP_Filesystem_Mission::write`` refuses it, without
the mock growing.

Driven over UDP on 127.0.0.1; no test asserts wall-clock time."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from gcs_planner.sim import ftp_server
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.aircraft.autopilot import ARDUPLANE
from gcs_planner.link import ftp
from gcs_planner.link.connection import Link, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.mission_ftp import HEADER, ITEM, as_stored
from gcs_planner.mission.items import MissionItem

FLAVOUR = ARDUPLANE.firmware
WAIT_S = 10.0


@contextmanager
def _vehicle(**kw: Any) -> Iterator[tuple[MockVehicle, int]]:
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=FLAVOUR, **kw) as vehicle:
        yield vehicle, port


def _client(port: int, transfer: str) -> MissionClient:
    client = MissionClient(open_link(f"udpout:127.0.0.1:{port}"), transfer=transfer)
    client.connect(timeout=WAIT_S)
    return client


# A mission whose storage shows: a _INT frame, millimetres of altitude, a command without a
# position sent in frame MISSION with x/y/z set, a loiter, a waypoint below home.
MIXED = [
    MissionItem(0, 0, 16, x=305_000_000, y=1_235_000_000, z=0.0),
    MissionItem(1, 6, 16, param2=30.0, x=305_010_000, y=1_235_000_000, z=100.129),
    MissionItem(2, 2, 178, param1=0.0, param2=22.0, param3=-1.0, x=7, y=8, z=9.5),
    MissionItem(3, 5, 18, param1=2.0, param3=150.0, x=305_020_000, y=1_235_010_000, z=250.987),
    MissionItem(4, 3, 16, x=305_030_000, y=1_235_020_000, z=-0.126),
    MissionItem(5, 5, 16, x=305_040_000, y=1_235_030_000, z=60.004),
]


def test_the_mission_protocol_and_mavftp_give_back_the_same_items():
    """Issue 51: the mock's two downloads of one mission differed (centimetres of altitude, the
    frame). ArduPilot builds both from the stored command (MissionItemProtocol_Waypoints::
    get_item and AP_Filesystem_Mission::read call AP_Mission::get_item)."""
    with _vehicle() as (vehicle, port):
        by_mission = _client(port, "mission")
        by_ftp = _client(port, "ftp")
        try:
            by_mission.upload(MIXED)
            got_mission = by_mission.download()
            got_ftp = by_ftp.download()
        finally:
            by_mission.link.close()
            by_ftp.link.close()
        assert by_ftp.transfer_used == "ftp" and by_mission.transfer_used == "mission"
        assert got_mission == got_ftp
        stored = vehicle.mission
    # What ArduPilot stores: frame as the altitude reference, whole centimetres, no x/y/z where
    # the command keeps none, autocontinue 1.
    frames = [it.frame for it in got_mission]
    assert frames == [0, 3, 0, 0, 3, 0]
    assert got_mission[1].z == as_stored(stored[1], 1).z
    assert abs(got_mission[1].z - 100.12) < 1e-4 and abs(got_mission[3].z - 250.98) < 1e-4
    assert (got_mission[2].x, got_mission[2].y, got_mission[2].z) == (0, 0, 0.0)
    assert all(it.autocontinue == 1 for it in got_mission)


def _ftp(
    link: Link, seq: int, session: int, opcode: int, offset: int = 0, data: bytes = b""
) -> Any:
    link.send(
        link.mav.file_transfer_protocol_encode(
            0, 1, 1, ftp.pack(seq, session, opcode, offset, data)
        )
    )
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        msg = link.recv(0.05)
        if msg is not None and msg.get_type() == "FILE_TRANSFER_PROTOCOL":
            reply = ftp.unpack(msg.payload)
            if reply.seq == (seq + 1) & 0xFFFF:
                return reply
    raise AssertionError(f"no reply to FTP opcode {opcode}")


def test_a_write_far_past_the_file_room_is_refused_and_grows_nothing():
    """Issue 51: one WriteFile at offset 400 MB grew the mock by 500 MB. ArduPilot's
    AP_Filesystem_Mission::write cannot grow its buffer there (ENOSPC), which GCS_FTP answers
    NAK FailErrno; a write within the room is taken."""
    with _vehicle(capacity=100) as (vehicle, port):
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            opened = _ftp(link, 1, 0, ftp.CREATE_FILE, data=ftp_server.MISSION_FILE.encode())
            assert opened.opcode == ftp.ACK
            session = opened.session
            far = _ftp(link, 2, session, ftp.WRITE_FILE, offset=400_000_000, data=b"\x01" * 200)
            assert (far.opcode, far.data[:2]) == (ftp.NAK, bytes([ftp.FAIL_ERRNO, 28]))
            (buf,) = [s.buf for s in vehicle.ftp.sessions.values() if s.mode == "write"]
            assert len(buf) == 0
            room = HEADER.size + 100 * ITEM.size
            edge = _ftp(link, 3, session, ftp.WRITE_FILE, offset=room - 10, data=b"\x01" * 10)
            assert edge.opcode == ftp.ACK and len(buf) == room
            past = _ftp(link, 4, session, ftp.WRITE_FILE, offset=room - 9, data=b"\x01" * 10)
            assert past.opcode == ftp.NAK and len(buf) == room
        finally:
            link.close()
