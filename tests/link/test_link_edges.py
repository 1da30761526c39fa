"""Issue 29 on the link: bad items refused before sending, and what the client says when an
upload goes wrong, each over real MAVLink on UDP 127.0.0.1 against the mock vehicle."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.cli import main
from gcs_planner.errors import LinkError
from gcs_planner.link.connection import Link, mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import item_to_message, mission_differences
from gcs_planner.mission.items import MissionItem

HOME = "0\t1\t0\t16\t0\t0\t0\t0\t30.5\t123.5\t10\t1"
ITEMS = [MissionItem(i, 0, 16, x=305_000_000 + 10 * i, y=1_235_000_000, z=100.0) for i in range(6)]


def _wait(link: Link, kind: str, seq: int | None = None, timeout: float = 10.0) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = link.recv(0.05)
        if msg is not None and msg.get_type() == kind and (seq is None or msg.seq == seq):
            return msg
    raise AssertionError(f"no {kind} {seq} within {timeout} s")


# 1. Items checked before anything is sent ------------------------------------------------------
@pytest.mark.parametrize(
    "row, field",
    [
        ("1\t0\t3\t16\t0\t0\t0\t0\t305000000\t123.5\t100\t1", "lat"),  # a latitude in degE7
        ("1\t0\t3\t16\t0\t0\t0\t0\t30.5\t-190\t100\t1", "lon"),
        ("1\t0\t3\t16\t0\t0\t0\t0\t30.5\t123.5\t1e30\t1", "alt"),
        ("1\t0\t3\t16\tinf\t0\t0\t0\t30.5\t123.5\t100\t1", "param1"),
        ("1\t0\t99\t16\t0\t0\t0\t0\t30.5\t123.5\t100\t1", "frame"),
        ("1\t0\t3\t65535\t0\t0\t0\t0\t30.5\t123.5\t100\t1", "command"),
    ],
)
def test_an_invalid_waypoints_row_is_refused_before_sending(tmp_path, capsys, row, field):
    wp = tmp_path / "m.waypoints"
    wp.write_text(f"QGC WPL 110\n{HOME}\n# a comment\n{row}\n")
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet"]
        assert main(["upload", str(wp), *conn]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err and "Traceback" not in err and "struct" not in err
        assert f"{wp}, row 4, field '{field}'" in err, err
        assert vehicle.mission == [] and vehicle.acks_sent == []  # nothing reached it


def test_an_unpackable_item_is_bad_input_from_the_library_too():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, target_system=1, target_component=1)
            bad = [ITEMS[0], MissionItem(1, 3, 16, x=305_000_000 * 10**7, y=0, z=10.0)]
            with pytest.raises(Exception) as info:
                client.upload(bad)
            assert info.type.__name__ == "InputError"
            assert "mission item 1" in str(info.value) and "lat" in str(info.value)
        finally:
            link.close()
        assert vehicle.acks_sent == []


# 3. Diagnoses ----------------------------------------------------------------------------------
def _die_mid_upload(link: Link, count: int, upto: int) -> None:
    """An upload that stops after item ``upto``: the vehicle is left waiting for the next."""
    link.send(link.mav.mission_count_encode(1, 1, count, 0))
    for seq in range(upto + 1):
        _wait(link, "MISSION_REQUEST_INT" if link.flavour == "px4" else "MISSION_REQUEST", seq)
        link.send(item_to_message(link.mav, ITEMS[seq], 1, 1))
    # The vehicle asks again for the item it waits for: it is still inside that transfer.
    _wait(link, "MISSION_REQUEST_INT" if link.flavour == "px4" else "MISSION_REQUEST", upto + 1)


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
@pytest.mark.parametrize("new_process", [False, True])
def test_an_upload_after_one_that_died_restarts_the_vehicle(flavour, new_process):
    port = free_udp_port()
    # Re-requests every 20 ms keep stale requests of the dead transfer in flight; the vehicle
    # would only give that transfer up after a minute.
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour, request_timeout=0.02,
                     upload_timeout=60.0) as vehicle:  # fmt: skip
        dead = open_link(f"udpout:127.0.0.1:{port}")
        dead.flavour = flavour  # type: ignore[attr-defined]
        dead.send(dead.mav.heartbeat_encode(6, 8, 0, 0, 4))
        _wait(dead, "HEARTBEAT")
        _die_mid_upload(dead, count=6, upto=2)
        link = open_link(f"udpout:127.0.0.1:{port}") if new_process else dead
        try:
            client = MissionClient(link)
            client.connect(timeout=10.0)
            want = ITEMS[:4]
            client.upload_verified(want)
            assert not mission_differences(want, vehicle.mission, skip_home=flavour == "ardupilot")
        finally:
            link.close()
            dead.close()


def _session(flavour: str = "px4", **kw: Any) -> tuple[MockVehicle, MissionClient]:
    port = free_udp_port()
    vehicle = MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour).start()
    link = open_link(f"udpout:127.0.0.1:{port}")
    client = MissionClient(link, **kw)
    client.connect(timeout=10.0)
    return vehicle, client


def test_a_vehicle_that_skips_an_item_is_named_as_such(monkeypatch):
    vehicle, client = _session()
    try:
        request = vehicle.missions._request

        def skip_two(up, now):
            if up.expected == 2:
                up.items.append(ITEMS[2])  # it pretends to hold item 2 and asks for 3
            request(up, now)

        monkeypatch.setattr(vehicle.missions, "_request", skip_two)
        with pytest.raises(LinkError) as info:
            client.upload(ITEMS)
        text = str(info.value)
        assert "requested item 3 after item 1" in text and "skipped item 2" in text, text
        assert "another ground station" not in text
    finally:
        client.link.close()
        vehicle.stop()


def test_an_early_acknowledgement_is_reported_with_its_result(monkeypatch):
    vehicle, client = _session(timeout=0.3, retries=2)
    try:
        on_item = vehicle.missions.on_item

        def ack_after_two(msg, peer, address):
            if msg.seq != 2 or vehicle.missions.upload is None:
                return on_item(msg, peer, address)
            vehicle.missions.upload = None  # item 2 ends it: "accepted", of 6 items
            # As PX4 ends a transfer: its _transfer_seq one past the item it took, so the same
            # item again is acknowledged again (handle_mission_item_both while idle).
            vehicle.missions.transfer_seq = 3
            vehicle.missions.ack(peer, mavlink.MAV_MISSION_ACCEPTED)

        monkeypatch.setattr(vehicle.missions, "on_item", ack_after_two)
        with pytest.raises(LinkError) as info:
            client.upload(ITEMS)
        text = str(info.value)
        assert "MISSION_ACK MAV_MISSION_ACCEPTED" in text and "after item 2" in text, text
        assert "stalled" not in text
    finally:
        client.link.close()
        vehicle.stop()


def test_a_read_back_without_an_answer_says_the_state_is_unknown(monkeypatch):
    vehicle, client = _session(timeout=0.2, retries=1)
    try:
        monkeypatch.setattr(vehicle.missions, "on_request_list", lambda msg, peer: None)
        with pytest.raises(LinkError) as info:
            client.upload_verified(ITEMS)
        text = str(info.value)
        assert "read-back failed" in text and "unknown" in text
        assert "most likely" not in text
    finally:
        client.link.close()
        vehicle.stop()


def test_the_heartbeat_wait_is_said_at_once(tmp_path):
    conn = f"udpout:127.0.0.1:{free_udp_port()}"  # nothing listens there
    proc = subprocess.Popen(
        [sys.executable, "-m", "gcs_planner", "download", "--connect", conn, "--wait", "60",
         "--out", str(tmp_path / "m.json")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        first = proc.stderr.readline()  # type: ignore[union-attr]
        assert f"waiting for a vehicle heartbeat on {conn} (up to 60 s)" in first
        assert proc.poll() is None  # said while it waits, not when the wait ends
    finally:
        proc.kill()
        proc.communicate()


def test_no_heartbeat_names_the_connection(tmp_path, capsys):
    conn = f"udpout:127.0.0.1:{free_udp_port()}"
    code = main(["download", "--connect", conn, "--wait", "1", "--out", str(tmp_path / "m.json")])
    captured = capsys.readouterr()
    assert code == 4 and captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 2 and lines[0].startswith("waiting for a vehicle heartbeat")
    assert f"no vehicle heartbeat on {conn} within 1 s" in lines[1], lines
    assert not (tmp_path / "m.json").exists()


def _free_tcp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def test_a_refused_tcp_connection_is_one_line_of_ours(tmp_path: Path, capsys):
    conn = f"tcp:127.0.0.1:{_free_tcp_port()}"
    code = main(["download", "--connect", conn, "--quiet", "--out", str(tmp_path / "m.json")])
    captured = capsys.readouterr()
    assert code == 4
    assert "sleeping" not in captured.out and captured.out == ""
    err = captured.err.strip()
    assert "\n" not in err and f"{conn} refused the connection" in err, err
