"""Missions by MAVLink FTP (@MISSION/mission.dat, as ArduPilot serves it): the file's layout,
upload and download over loopback and over the emulated SiK radio with burst loss, a 5 s fade
in the middle of a burst read, the read-back by FTP, the fall back to the mission protocol
where the vehicle has no mission file (PX4), and hostile replies.

No test asserts wall-clock time; deadlines are generous and what is compared is what the
vehicle and the radio counted."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace

import pytest
from gcs_planner.sim import ftp_server
from gcs_planner.sim.radio import RadioConfig, SikRadio
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.cli import main
from gcs_planner.errors import LinkError
from gcs_planner.link import ftp
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient, ReadBackError
from gcs_planner.link.mission_ftp import (
    ITEM,
    as_stored,
    crc32,
    decode_mission,
    encode_mission,
    mission_length,
    stored_file,
    stored_item_bytes,
)
from gcs_planner.link.protocol import item_differences, mission_differences
from gcs_planner.mission.items import MissionItem

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits


def _mission(n: int) -> list[MissionItem]:
    return [
        MissionItem(i, 0, 16, x=305_000_000 + 97 * i, y=1_235_000_000 + 89 * i, z=500.0 + i % 7)
        for i in range(n)
    ]


def _holds(vehicle: MockVehicle, items: list[MissionItem]) -> bool:
    return not mission_differences(items, vehicle.mission, skip_home=vehicle.flavour == "ardupilot")


@contextmanager
def _loopback(
    flavour: str = "ardupilot", **client: object
) -> Iterator[tuple[MockVehicle, MissionClient]]:
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour, capacity=2000) as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            c = MissionClient(link, **client)  # type: ignore[arg-type]
            c.connect(timeout=10.0)
            yield vehicle, c
        finally:
            link.close()


@contextmanager
def _over_radio(**radio: object) -> Iterator[tuple[MockVehicle, SikRadio, MissionClient]]:
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", capacity=2000) as vehicle:
        with SikRadio("udpin:127.0.0.1:0", f"udpout:127.0.0.1:{port}", RadioConfig(**radio)) as r:  # type: ignore[arg-type]
            link = open_link(r.ground_connection)
            try:
                c = MissionClient(link, transfer="auto")
                c.connect(timeout=30.0)
                yield vehicle, r, c
            finally:
                link.close()


# The file ------------------------------------------------------------------------------------
def test_mission_dat_is_ardupilots_header_and_item_int_payloads():
    items = _mission(3)
    data = encode_mission(items)
    # struct header: magic 0x763d, data_type 0, options 0, start 0, num_items; then 38 bytes
    # (MISSION_ITEM_INT's payload) per item.
    assert data[:10] == bytes([0x3D, 0x76, 0, 0, 0, 0, 0, 0, 3, 0])
    assert len(data) == 10 + 3 * 38 == mission_length(data[:10])
    assert [(it.x, it.y, it.z) for it in decode_mission(data)] == [
        (it.x, it.y, it.z) for it in items
    ]
    with pytest.raises(LinkError, match="magic"):
        mission_length(b"\x00" * 10)
    with pytest.raises(LinkError, match="header's 3 items"):
        decode_mission(data + b"\x01")


def test_payload_round_trip_and_an_oversized_size_is_refused():
    p = ftp.unpack(ftp.pack(7, 2, ftp.READ_FILE, 478, b"abc"))
    assert (p.seq, p.session, p.opcode, p.offset, p.data) == (7, 2, ftp.READ_FILE, 478, b"abc")
    raw = ftp.pack(7, 2, ftp.ACK, 0, b"")
    raw[4] = 250
    with pytest.raises(ftp.FtpError, match="250 data bytes"):
        ftp.unpack(raw)


def test_crc32_is_ardupilots_crc_crc32_from_zero():
    # crc_crc32 (AP_Math/crc.cpp): crc = tab[(crc ^ byte) & 0xff] ^ (crc >> 8), the table of the
    # reflected polynomial 0xEDB88320; AP_Filesystem::crc32 starts from 0 and does not invert.
    def bitwise(data: bytes, crc: int = 0) -> int:
        for byte in data:
            crc ^= byte
            for _ in range(8):
                crc = (crc >> 1) ^ (0xEDB88320 if crc & 1 else 0)
        return crc

    for data in (b"", b"123456789", encode_mission(_mission(40))):
        assert crc32(data) == bitwise(data)
    assert crc32(b"123456789") == 0x2DFD2D88  # not zlib's 0xCBF43926: no inversions
    assert crc32(b"6789", crc32(b"12345")) == crc32(b"123456789")  # read 64 bytes at a time


def test_the_stored_file_is_what_get_item_gives_back():
    sent = MissionItem(3, 6, 16, current=1, autocontinue=0, param2=30.0, x=1, y=2, z=100.129)
    got = as_stored(sent, 3)
    # RELATIVE_ALT_INT is kept as a flag and given back as GLOBAL_RELATIVE_ALT; the altitude
    # in whole centimetres (truncated); autocontinue 1; current 0 (no mission running).
    assert (got.frame, got.autocontinue, got.current, got.param2) == (3, 1, 0, 30.0)
    assert got.z == pytest.approx(100.12, abs=1e-5)
    assert as_stored(MissionItem(3, 0, 177, param1=2.0, z=1.2345), 3).z == 1.2345  # no Location
    raw = stored_item_bytes(sent, 3)
    assert len(raw) == ITEM.size and raw[32:34] == bytes([1, 1])  # get_item's target 1/1
    home = stored_item_bytes(MissionItem(0, 0, 16, x=9, y=9, z=5.0), 0)
    assert len(stored_file([sent, sent], home)) == 10 + 2 * ITEM.size
    # Read back by either way, a command without a position comes back with frame 0 from
    # ArduPilot whether it was sent as 0 or as 2 (MAV_FRAME_MISSION): not a difference; a
    # waypoint's frame still is.
    speed = MissionItem(4, 2, 178, param2=22.0)
    assert as_stored(speed, 4).frame == 0 and not item_differences(speed, as_stored(speed, 4))
    assert item_differences(MissionItem(4, 2, 16), MissionItem(4, 0, 16))


# Transfers -----------------------------------------------------------------------------------
def test_upload_and_download_by_ftp_over_loopback():
    items = _mission(300)
    with _loopback() as (vehicle, client):  # the library's default, auto, as the CLI's
        report = client.upload_verified(items)
        assert report.transfer == "ftp" and _holds(vehicle, items)
        assert vehicle.ftp.writes_stored == 1
        assert vehicle.acks_sent == []  # not one MISSION_ACK: the mission protocol was not used
        assert client.autopilot_capabilities() & ftp_capability()
        got = client.download()
        assert client.transfer_used == "ftp"
        assert [(it.x, it.y) for it in got[1:]] == [(it.x, it.y) for it in items[1:]]
        # The read's session was closed by its TerminateSession: numbered past the burst's
        # end-of-file NAK, it was not taken for a re-request of that NAK (GCS_FTP::worker).
        assert not _open_files(vehicle)


def _open_files(vehicle: MockVehicle) -> list[str]:
    """The modes of the vehicle's FTP sessions that hold a file open."""
    return [s.mode for s in vehicle.ftp.sessions.values() if s.mode]


def test_every_download_terminates_its_session_at_the_first_request():
    """Before the fix each download's TerminateSession went unanswered for its 6 attempts
    (6-9 s) and left the session open on the vehicle. A mission of one burst packet: the
    file's bytes are all in before the burst's end-of-file NAK comes."""
    items = _mission(4)
    with _loopback() as (vehicle, client):
        client.upload_verified(items)
        for _ in range(3):
            before = vehicle.ftp.requests
            client.download()
            assert client.transfer_used == "ftp" and not _open_files(vehicle)
            # open, burst read, terminate, and the file's CRC that checks what was read:
            # nothing asked twice on a link that loses nothing
            assert vehicle.ftp.requests - before == 4


def ftp_capability() -> int:
    from gcs_planner.link.connection import mavlink

    return mavlink.MAV_PROTOCOL_CAPABILITY_FTP


def test_upload_by_ftp_over_a_radio_with_burst_loss():
    items = _mission(200)
    with _over_radio(loss=0.05, burst=4.0, seed=7) as (vehicle, r, client):
        report = client.upload_verified(items)
        assert report.transfer == "ftp" and _holds(vehicle, items)
        assert r.counts.packets_lost > 0  # there was loss, and the missing ranges were asked again
        got = client.download()
        assert [(it.x, it.y) for it in got[1:]] == [(it.x, it.y) for it in items[1:]]


def test_a_5_s_fade_in_the_middle_of_a_burst_read_is_survived():
    # 150 items (5,710 bytes), the fade from byte 2,500: a read that gives up after 1.5 s of
    # silence fails here; the bytes around the fade are only the way in and out.
    items = _mission(150)
    with _over_radio(loss=0.0, seed=3) as (vehicle, r, client):
        vehicle.missions.commit(items)
        faded = threading.Event()

        def watch() -> None:
            deadline = time.monotonic() + 300.0
            while time.monotonic() < deadline:
                b = vehicle.ftp._burst
                if b is not None and b.offset > 2500:
                    r.fade(5.0)
                    faded.set()
                    return
                time.sleep(0.01)

        t = threading.Thread(target=watch, daemon=True)
        t.start()
        got = client.download()
        t.join(timeout=5.0)
        assert faded.is_set() and client.transfer_used == "ftp"
        assert [(it.x, it.y) for it in got[1:]] == [(it.x, it.y) for it in items[1:]]
        assert client.retry_count > 0  # the ranges the fade took were asked again


def test_a_read_whose_session_the_vehicle_closed_resumes_in_a_new_one():
    items = _mission(200)
    with _loopback(transfer="ftp", timeout=0.5) as (vehicle, client):
        vehicle.missions.commit(items)
        timers = vehicle.ftp.timers
        closed = []

        def closing(now: float) -> None:  # GCS_FTP push_reply: a reply that cannot go for 3 s
            b = vehicle.ftp._burst
            if b is not None and b.offset > 2000 and not closed:
                vehicle.ftp.sessions.clear()
                vehicle.ftp._burst = None
                closed.append(b.offset)
            timers(now)

        vehicle.ftp.timers = closing  # type: ignore[method-assign]
        got = client.download()
        assert closed and client.transfer_used == "ftp"
        assert [(it.x, it.y) for it in got[1:]] == [(it.x, it.y) for it in items[1:]]


def test_an_upload_whose_open_ack_was_lost_resets_and_opens_again():
    items = _mission(40)
    with _loopback(transfer="ftp", timeout=0.5) as (vehicle, client):
        send = vehicle.ftp._send_payload
        dropped = []

        def lose_first_open_ack(peer, payload):
            p = ftp.unpack(payload)
            if p.req_opcode == ftp.CREATE_FILE and p.opcode == ftp.ACK and not dropped:
                dropped.append(p.session)
                return
            send(peer, payload)

        vehicle.ftp._send_payload = lose_first_open_ack  # type: ignore[method-assign]
        report = client.upload_verified(items)
        assert dropped and report.transfer == "ftp" and _holds(vehicle, items)


def test_an_open_refused_after_each_resend_is_asked_again_after_a_reset_each_time():
    # At 30 % loss each way about three opens in ten lose their ACK and are refused on the
    # resend (the first copy holds the file): three opens in a row, one upload in 40.
    items = _mission(40)
    with _loopback(transfer="ftp", timeout=0.5) as (vehicle, client):
        send = vehicle.ftp._send_payload
        dropped: list[int] = []
        refusals: list[bytes] = []

        def lose_open_acks(peer, payload):
            p = ftp.unpack(payload)
            if p.req_opcode == ftp.CREATE_FILE and p.opcode == ftp.ACK:
                if len(dropped) < client.retries:
                    dropped.append(p.session)
                    return
            if p.req_opcode == ftp.CREATE_FILE and p.opcode == ftp.NAK:
                refusals.append(p.data)
            send(peer, payload)

        vehicle.ftp._send_payload = lose_open_acks  # type: ignore[method-assign]
        report = client.upload_verified(items)
        assert len(dropped) == client.retries == 5
        # ArduPilot's answer to the resend: FailErrno (AP_Filesystem_Mission::open's one
        # upload at a time), with the errno the open left as it was.
        assert refusals and {r[0] for r in refusals} == {ftp.FAIL_ERRNO}
        assert report.transfer == "ftp" and _holds(vehicle, items)


def _hold_the_mission_file(vehicle: MockVehicle) -> None:
    """Another ground station (system 200) is uploading: its session holds mission.dat."""
    other = (200, 190)
    vehicle.ftp.sessions[(other, 77)] = ftp_server._Session(77, other, mode="write")


def test_a_mission_file_another_upload_holds_sends_auto_to_the_mission_protocol():
    items = _mission(30)
    with _loopback(timeout=0.5) as (vehicle, client):
        _hold_the_mission_file(vehicle)
        report = client.upload_verified(items)
        assert report.transfer == "mission" and _holds(vehicle, items)
        assert vehicle.ftp.writes_stored == 0
    with _loopback(transfer="ftp", timeout=0.5) as (vehicle, client):
        _hold_the_mission_file(vehicle)
        with pytest.raises(ftp.FtpBusy, match="refused 6 times.*another ground station"):
            client.upload_verified(items)
        assert vehicle.ftp.writes_stored == 0


def test_the_read_back_by_ftp_tells_differs_from_could_not_read():
    items = _mission(20)
    with _loopback(transfer="ftp") as (vehicle, client):
        real = vehicle.ftp._parse

        def shifted(data: bytes):  # the vehicle stores something else than it was sent
            got = real(data)
            return [got[0], *[it.with_seq(it.seq) for it in got[2:]], got[1]]

        vehicle.ftp._parse = shifted  # type: ignore[method-assign]
        with pytest.raises(LinkError, match="differs") as err:
            client.upload_verified(items)
        assert not isinstance(err.value, ReadBackError)
    with _loopback(transfer="ftp", timeout=0.3, retries=1) as (vehicle, client):
        handle = vehicle.ftp.handle

        def no_reads(msg, peer):  # the write goes through, no read is ever answered
            if ftp.unpack(msg.payload).opcode == ftp.OPEN_FILE_RO:
                return
            handle(msg, peer)

        vehicle.ftp.handle = no_reads  # type: ignore[method-assign]
        with pytest.raises(ReadBackError, match="could not be read back"):
            client.upload_verified(items)
        assert _holds(vehicle, items)


def _opcodes_served(vehicle: MockVehicle) -> list[int]:
    seen: list[int] = []
    handle = vehicle.ftp.handle

    def counting(msg, peer):
        seen.append(ftp.unpack(msg.payload).opcode)
        handle(msg, peer)

    vehicle.ftp.handle = counting  # type: ignore[method-assign]
    return seen


def test_an_upload_is_verified_by_the_vehicles_crc_without_reading_the_file_back():
    items = _mission(300)
    with _loopback(transfer="ftp") as (vehicle, client):
        seen = _opcodes_served(vehicle)
        report = client.upload_verified(items)
        assert (report.transfer, report.verify, report.crc_note) == ("ftp", "crc", "")
        assert vehicle.ftp.crcs_served == 1 and _holds(vehicle, items)
        # The file's first item (the vehicle's home) by one ReadFile; no burst read.
        assert ftp.BURST_READ_FILE not in seen and seen.count(ftp.READ_FILE) == 1
        # The vehicle's home is not the item 0 sent, and the CRC matched all the same.
        assert vehicle.mission[0] != items[0]
    with _loopback(transfer="ftp", verify="read") as (vehicle, client):
        seen = _opcodes_served(vehicle)
        report = client.upload_verified(items)
        assert report.verify == "read" and vehicle.ftp.crcs_served == 0
        assert ftp.BURST_READ_FILE in seen


def test_a_command_without_a_position_after_home_verifies_both_ways():
    # As the planner's missions begin: home, a speed change (no position), waypoints. In
    # ArduPilot's file the speed change carries the home's x, y, z (get_item leaves them in the
    # read call's item buffer), which the CRC's 64-byte reads and a 239-byte burst both see.
    speed = MissionItem(1, 2, 178, param1=0.0, param2=22.0, param3=-1.0)
    items = [_mission(1)[0], speed, *[it.with_seq(i + 2) for i, it in enumerate(_mission(40))]]
    with _loopback(transfer="ftp") as (vehicle, client):
        vehicle.missions.commit(items)
        read = ftp_server.mission_reader(vehicle.missions.mission, None)
        home_x = vehicle.mission[0].x
        assert ITEM.unpack_from(read(0, 239), 10 + ITEM.size)[4] == home_x != 0
        report = client.upload_verified(items)
        assert report.verify == "crc" and _holds(vehicle, items)
        got = client.download()
        assert (got[1].x, got[1].y, got[1].z) == (0, 0, 0.0)  # leftovers, not the vehicle's
    with _loopback(transfer="ftp", verify="read") as (vehicle, client):
        assert client.upload_verified(items).verify == "read" and _holds(vehicle, items)


def test_the_crc_never_verifies_a_mission_the_vehicle_did_not_store():
    items = _mission(30)
    with _loopback(transfer="ftp") as (vehicle, client):
        real = vehicle.ftp._parse

        def one_item_off(data: bytes):  # stores item 7 a centimetre east of where it was sent
            got = real(data)
            return [*got[:7], replace(got[7], y=got[7].y + 1000), *got[8:]]

        vehicle.ftp._parse = one_item_off  # type: ignore[method-assign]
        with pytest.raises(LinkError, match="item 7: y") as err:
            client.upload_verified(items)
        assert not isinstance(err.value, ReadBackError) and vehicle.ftp.crcs_served == 1
    with _loopback(transfer="ftp") as (vehicle, client):
        real = vehicle.ftp._parse
        vehicle.ftp._parse = lambda data: real(data)[:-1]  # type: ignore[method-assign]
        with pytest.raises(LinkError, match="holds 29 items, 30 were uploaded"):
            client.upload_verified(items)


def test_a_crc_that_differs_or_is_not_answered_leaves_the_verdict_to_the_read_back():
    items = _mission(30)
    # The vehicle stores a parameter a hair off (as an autopilot storing it narrower would):
    # the CRC differs, the read-back finds it the same item within tolerance.
    with _loopback(transfer="ftp") as (vehicle, client):
        real = vehicle.ftp._parse

        def narrower(data: bytes):
            got = real(data)
            return [*got[:5], replace(got[5], param1=got[5].param1 + 1e-5), *got[6:]]

        vehicle.ftp._parse = narrower  # type: ignore[method-assign]
        report = client.upload_verified(items)
        assert report.verify == "read" and "CRC 0x" in report.crc_note
    # An ArduPilot that does not know CalcFileCRC32.
    with _loopback(transfer="ftp") as (vehicle, client):
        handle = vehicle.ftp.handle

        def no_crc(msg, peer):
            p = ftp.unpack(msg.payload)
            if p.opcode == ftp.CALC_FILE_CRC32:
                vehicle.ftp._nak(peer, p, ftp.UNKNOWN_COMMAND)
                return
            handle(msg, peer)

        vehicle.ftp.handle = no_crc  # type: ignore[method-assign]
        report = client.upload_verified(items)
        assert report.verify == "read" and "unknown command" in report.crc_note
        assert _holds(vehicle, items)


def test_a_5_s_fade_in_the_middle_of_an_ftp_upload_is_survived():
    # 150 items: a write that gives up after 1.5 s of silence fails here, as with more.
    items = _mission(150)
    half = len(encode_mission(items)) // 2
    with _over_radio(loss=0.0, seed=5) as (vehicle, r, client):
        faded = threading.Event()

        def watch() -> None:
            deadline = time.monotonic() + 300.0
            while time.monotonic() < deadline:
                writing = [s for s in list(vehicle.ftp.sessions.values()) if s.mode == "write"]
                if writing and len(writing[0].buf) > half:
                    r.fade(5.0)
                    faded.set()
                    return
                time.sleep(0.01)

        t = threading.Thread(target=watch, daemon=True)
        t.start()
        report = client.upload_verified(items)
        t.join(timeout=5.0)
        assert faded.is_set() and report.transfer == "ftp" and _holds(vehicle, items)
        assert vehicle.ftp.writes_stored == 1 and report.retries > 0  # pieces the fade took


def test_px4_falls_back_to_the_mission_protocol():
    items = _mission(15)
    with _loopback("px4", transfer="auto") as (vehicle, client):
        report = client.upload_verified(items)
        assert report.transfer == "mission" and _holds(vehicle, items)
        assert vehicle.ftp.writes_stored == 0
    with _loopback("ardupilot", transfer="auto") as (vehicle, client):
        vehicle.ftp_enabled = False  # an ArduPilot built without MAVFTP
        assert client.upload_verified(items).transfer == "mission" and _holds(vehicle, items)
    with _loopback("px4", transfer="ftp") as (vehicle, client):
        with pytest.raises(LinkError, match="file not found"):
            client.upload_verified(items)


def test_an_ftp_that_never_answers_sends_auto_to_the_mission_protocol():
    # At 30 % loss each way one FTP exchange in about 60 goes unanswered through its six
    # attempts (0.51 ** 6); here every one does, and the capability still says FTP.
    items = _mission(15)
    with _loopback(transfer="auto", timeout=0.3, retries=2) as (vehicle, client):
        vehicle.ftp.handle = lambda msg, peer: None  # type: ignore[method-assign]
        report = client.upload_verified(items)
        assert report.transfer == "mission" and _holds(vehicle, items)
        assert vehicle.ftp.writes_stored == 0
    with _loopback(transfer="ftp", timeout=0.3, retries=2) as (vehicle, client):
        vehicle.ftp.handle = lambda msg, peer: None  # type: ignore[method-assign]
        with pytest.raises(ftp.FtpQuiet, match="ResetSessions: no answer after 3 attempts"):
            client.upload_verified(items)


def test_an_ardupilot_refusing_the_file_is_an_error_and_keeps_its_mission():
    items = [*_mission(5), MissionItem(5, 0, 4242, x=1, y=1, z=1.0)]  # a command it lacks
    with _loopback(transfer="ftp") as (vehicle, client):
        before = vehicle.mission
        with pytest.raises(LinkError, match="did not store"):
            client.upload_verified(items)
        assert vehicle.mission == before


# Hostile replies ----------------------------------------------------------------------------
def _tamper(vehicle: MockVehicle, change) -> None:
    send = vehicle.ftp._send_payload

    def tampered(peer, payload):
        p = ftp.unpack(payload)
        if p.req_opcode in (ftp.READ_FILE, ftp.BURST_READ_FILE) and p.opcode == ftp.ACK:
            payload = change(list(payload))
        send(peer, payload)

    vehicle.ftp._send_payload = tampered  # type: ignore[method-assign]


def test_hostile_replies_are_clear_errors(monkeypatch):
    def oversize(payload):
        payload[4] = 250
        return payload

    def other_session(payload):
        payload[2] = (payload[2] + 1) % 256
        return payload

    for change, message in ((oversize, "250 data bytes"), (other_session, "not ours")):
        with _loopback(transfer="ftp", timeout=0.3, retries=1) as (vehicle, client):
            vehicle.missions.commit(_mission(30))
            _tamper(vehicle, change)
            with pytest.raises(LinkError, match=message):
                client.download()
    # A file longer than its header says: bytes past its end.
    real_reader = ftp_server.mission_reader

    def longer(items, nav):
        real = real_reader(items, nav)
        whole = bytearray()
        while piece := real(len(whole), 239):
            whole += piece
        data = bytes(whole) + b"\x01" * 300
        return lambda offset, size: data[offset : offset + size]

    monkeypatch.setattr(ftp_server, "mission_reader", longer)
    with _loopback(transfer="ftp", timeout=0.3, retries=1) as (vehicle, client):
        vehicle.missions.commit(_mission(30))
        with pytest.raises(LinkError, match="past its end"):
            client.download()


def test_upload_and_download_commands_go_by_ftp_and_say_so(tmp_path, capsys):
    from gcs_planner.mission.waypoints import dumps_items

    items = [
        MissionItem(i, 0, 16, param2=30.0, x=305_000_000 + 500 * i, y=1_235_000_000, z=120.0)
        for i in range(12)
    ]
    wp = tmp_path / "m.waypoints"
    wp.write_text(dumps_items(items, "ardupilot", (30.5, 123.5, 0.0)))
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}") as vehicle:
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet"]
        assert main(["upload", str(wp), *conn, "--keep-loiter-radius"]) == 0
        assert "uploaded and verified 12 items" in (out := capsys.readouterr().out)
        assert "by MAVFTP" in out and vehicle.ftp.writes_stored == 1
        assert "checked by the vehicle's CRC" in out and vehicle.ftp.crcs_served == 1
        assert main(["upload", str(wp), *conn, "--keep-loiter-radius", "--verify", "read"]) == 0
        assert "CRC" not in capsys.readouterr().out and vehicle.ftp.crcs_served == 1
        back = tmp_path / "back.json"
        assert main(["download", *conn, "--out", str(back), "--transfer", "mission"]) == 0
        assert "by MAVFTP" not in capsys.readouterr().out  # the flag chose the mission protocol
        assert _holds(vehicle, items)


def test_a_garbage_mission_file_is_a_one_line_error_from_download(monkeypatch, tmp_path, capsys):
    garbage = b"\x55" * 700
    monkeypatch.setattr(
        ftp_server, "mission_reader", lambda items, nav: lambda o, n: garbage[o : o + n]
    )
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}"):
        out = tmp_path / "m.json"
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet", "--transfer", "auto"]
        code = main(["download", *conn, "--out", str(out), "--timeout", "0.5", "--retries", "1"])
    err = capsys.readouterr().err
    assert code == 4 and not out.exists()
    assert "not a mission file" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
