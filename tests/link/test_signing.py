"""MAVLink 2 signing between the client and the mock vehicle: right key works, others refused."""

from __future__ import annotations

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.errors import LinkError
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.signing import key_from_passphrase
from gcs_planner.mission.items import MissionItem

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

ITEMS = [MissionItem(i, 0, 16, x=305_000_000 + i, y=1_235_000_000, z=100.0) for i in range(5)]


def _client(port: int, key: bytes | None) -> MissionClient:
    link = open_link(f"udpout:127.0.0.1:{port}", signing_key=key)
    return MissionClient(link, timeout=0.3, retries=1)


def test_key_from_passphrase():
    key = key_from_passphrase("correct horse")
    assert len(key) == 32
    assert key != key_from_passphrase("correct horsf")
    with pytest.raises(ValueError):
        key_from_passphrase("")


def test_right_key_works():
    key = key_from_passphrase("sea-trial")
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=key) as vehicle:
        client = _client(port, key)
        try:
            client.connect(timeout=5.0)
            client.upload_verified(ITEMS)
        finally:
            client.link.close()
        assert vehicle.mission == ITEMS
        assert vehicle.refused_signature == 0


def test_wrong_key_is_refused_by_both_ends():
    port = free_udp_port()
    vehicle_key = key_from_passphrase("sea-trial")
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=vehicle_key) as vehicle:
        client = _client(port, key_from_passphrase("not-the-key"))
        try:
            with pytest.raises(LinkError, match="unsigned or signed with another key"):
                client.connect(timeout=2.5)
        finally:
            client.link.close()
        assert vehicle.refused_signature > 0
        assert vehicle.mission == []


def test_unsigned_vehicle_is_refused_by_a_signing_client():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4"):
        client = _client(port, key_from_passphrase("sea-trial"))
        try:
            with pytest.raises(LinkError, match="unsigned or signed with another key"):
                client.connect(timeout=2.5)
        finally:
            client.link.close()


def test_unsigned_client_is_refused_by_a_signing_vehicle():
    port = free_udp_port()
    key = key_from_passphrase("sea-trial")
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=key) as vehicle:
        client = _client(port, None)
        try:
            # The unsigned client can hear the vehicle but nothing it sends is accepted.
            client.connect(timeout=5.0)
            with pytest.raises(LinkError, match="no answer"):
                client.upload(ITEMS)
        finally:
            client.link.close()
        assert vehicle.refused_signature > 0
        assert vehicle.mission == []


# The signature check as the specification orders it ---------------------------------------------
KEY = key_from_passphrase("sea-trial")
OTHER = key_from_passphrase("not-the-key")
FUTURE = 2**47  # 10-microsecond units: centuries ahead of any clock


def _mav(key: bytes, system: int = 255, component: int = 190, timestamp: int | None = None):
    """A pymavlink MAVLink object signing with ``key`` on link 7, through our own check."""
    from pymavlink import mavutil

    from gcs_planner.link.signing import enable_signing

    class _Sink:
        def write(self, buf: bytes) -> None:
            pass

    mav = mavutil.mavlink.MAVLink(_Sink(), srcSystem=system, srcComponent=component)

    class _Conn:
        def setup_signing(self, key, sign_outgoing, allow_unsigned_callback):
            mav.signing.secret_key = key
            mav.signing.sign_outgoing = sign_outgoing
            mav.signing.allow_unsigned_callback = allow_unsigned_callback
            mav.signing.link_id = 7
            mav.signing.timestamp = 1_000_000_000 if timestamp is None else timestamp

    conn = _Conn()
    conn.mav = mav
    enable_signing(conn, key)
    return mav


def _frame(sender, text: bytes = b"hi") -> bytes:
    return bytes(sender.statustext_encode(6, text).pack(sender))


def _accepted(receiver, frame: bytes) -> bool:
    from pymavlink import mavutil

    try:
        receiver.decode(bytearray(frame))
    except mavutil.mavlink.MAVError:
        return False
    return True


def test_a_wrong_key_frame_from_the_future_does_not_lock_the_rightful_peer_out():
    receiver = _mav(KEY, system=1, component=1)
    rightful = _mav(KEY)
    attacker = _mav(OTHER, timestamp=FUTURE)  # same link id, system and component
    assert _accepted(receiver, _frame(rightful))
    assert not _accepted(receiver, _frame(attacker))
    assert _accepted(receiver, _frame(rightful))
    assert receiver.signing.timestamp < FUTURE  # our own clock was not dragged forward either


def test_replays_and_stale_frames_are_refused():
    receiver = _mav(KEY, system=1, component=1)
    sender = _mav(KEY)
    first, second = _frame(sender, b"one"), _frame(sender, b"two")
    assert _accepted(receiver, first)
    assert _accepted(receiver, second)
    assert not _accepted(receiver, first)  # older than the stream's last frame
    assert not _accepted(receiver, second)  # a replay of the last one
    stale = _mav(KEY, system=9, timestamp=1_000_000_000 - 7_000_000)  # a new stream, > 1 min old
    assert not _accepted(receiver, _frame(stale))


def test_a_tampered_frame_is_refused():
    receiver = _mav(KEY, system=1, component=1)
    frame = bytearray(_frame(_mav(KEY), b"abc"))
    frame[-13] ^= 1  # the link id is covered by the signature
    assert not _accepted(receiver, bytes(frame))


def test_future_wrong_key_frame_does_not_lock_out_the_ground_station_end_to_end():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=KEY) as vehicle:
        rightful = _client(port, KEY)
        attacker = open_link(f"udpout:127.0.0.1:{port}", signing_key=OTHER)
        try:
            signing = attacker.conn.mav.signing
            signing.link_id = rightful.link.conn.mav.signing.link_id
            signing.timestamp = FUTURE
            for _ in range(3):
                attacker.send(attacker.mav.heartbeat_encode(6, 8, 0, 0, 4))
            rightful.connect(timeout=5.0)
            rightful.upload_verified(ITEMS)
        finally:
            attacker.close()
            rightful.link.close()
        assert vehicle.mission == ITEMS
        assert vehicle.refused_signature >= 1


def test_a_replayed_clear_is_refused_by_the_vehicle():
    port = free_udp_port()
    # Link-level duplicate dropping is off so that the signature check is what refuses it.
    with MockVehicle(
        f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=KEY, drop_link_duplicates=False
    ) as vehicle:
        client = _client(port, KEY)
        try:
            client.connect(timeout=5.0)
            clear = client.mav.mission_clear_all_encode(1, 1, 0)
            recorded = bytes(clear.pack(client.mav))
            client.link.write_raw(recorded)
            client.upload_verified(ITEMS)
            refused = vehicle.refused_signature
            client.link.write_raw(recorded)  # an eavesdropper's copy, sent again
            client.connect(timeout=5.0)  # a round trip: the replay has been handled by now
            assert len(client.download()) == len(ITEMS)
        finally:
            client.link.close()
        assert vehicle.mission == ITEMS
        assert vehicle.refused_signature > refused


def test_unsigned_upload_to_a_signed_vehicle_names_the_signing_key_flag(tmp_path, capsys):
    from gcs_planner.cli import main

    plan = tmp_path / "m.waypoints"
    plan.write_text("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t30.5\t123.5\t10\t1\n"
                    "1\t0\t0\t16\t0\t0\t0\t0\t30.6\t123.5\t10\t1\n")  # fmt: skip
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=KEY) as vehicle:
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet", "--timeout", "0.3"]
        assert main(["upload", str(plan), *conn, "--retries", "1"]) == 4
        assert vehicle.mission == []
    err = capsys.readouterr().err
    assert "--signing-key" in err and "\n" not in err.strip()


# The radio's own reports on a signed link ----------------------------------------------------
def test_the_radios_unsigned_radio_status_reaches_the_pacing_on_a_signed_link():
    """A keyed ground station refused the radio's RADIO_STATUS (the radio knows no key): the
    pacing built for it never ran. ArduPilot (GCS_Signing.cpp, accept_unsigned_callback) and
    PX4 (mavlink_sign_control.cpp, accept_unsigned) take it unsigned; anything else unsigned
    is still refused."""
    import socket

    from gcs_planner.link.connection import mavlink
    from gcs_planner.link.session import VehicleSession

    port = free_udp_port()
    link = open_link(f"udpin:127.0.0.1:{port}", signing_key=KEY)
    try:
        session = VehicleSession(link)
        radio = mavlink.MAVLink(None, srcSystem=51, srcComponent=68)  # SiK's ids
        stranger = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for msg, mav in (
                (radio.radio_status_encode(200, 190, 25, 40, 40, 0, 0), radio),
                (stranger.heartbeat_encode(1, 3, 0, 0, 4), stranger),
                (radio.radio_encode(200, 190, 25, 40, 40, 0, 0), radio),  # SiK's older report
            ):
                sock.sendto(bytes(msg.pack(mav)), ("127.0.0.1", port))
            assert session._recv(1.0, {"HEARTBEAT"}, None) is None
        assert session.radio.reports == 2 and session.radio.congested()  # 25 % free: the gate
        assert link.refused_signature == 1  # the unsigned heartbeat
    finally:
        link.close()


def test_radio_status_reaches_a_signed_client_through_the_emulated_sik_radio():
    from gcs_planner.sim.radio import RadioConfig, SikRadio

    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", signing_key=KEY) as vehicle:
        with SikRadio("udpin:127.0.0.1:0", f"udpout:127.0.0.1:{port}", RadioConfig()) as r:
            link = open_link(r.ground_connection, signing_key=KEY)
            try:
                client = MissionClient(link, transfer="mission")
                client.connect(timeout=30.0)
                client.upload_verified(ITEMS)
            finally:
                link.close()
        assert r.counts.statuses > 0 and client.radio.reports > 0
        assert link.refused_signature == 0
        assert len(vehicle.mission) == len(ITEMS)


def test_unsigned_ftp_upload_to_a_signed_vehicle_names_the_signing_key_flag(tmp_path, capsys):
    from gcs_planner.cli import main

    plan = tmp_path / "m.waypoints"
    plan.write_text("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t30.5\t123.5\t10\t1\n"
                    "1\t0\t0\t16\t0\t0\t0\t0\t30.6\t123.5\t10\t1\n")  # fmt: skip
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="ardupilot", signing_key=KEY) as vehicle:
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet", "--timeout", "0.3"]
        code = main(["upload", str(plan), *conn, "--retries", "1", "--transfer", "ftp"])
        assert code == 4 and vehicle.ftp.writes_stored == 0
    err = capsys.readouterr().err
    assert "MAVFTP" in err and "--signing-key" in err and "\n" not in err.strip()
