"""Missions over the emulated SiK radio (sim/radio.py): its timing and channel, the honest txbuf,
and the ground station's transfers through it: upload, download, read-back, and a 5 s fade in
the middle of a transfer that the transfer survives.

No test asserts wall-clock time: waits are generous deadlines for events, and what is compared
is what the radio and the vehicle counted."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest
from gcs_planner.sim.radio import GilbertElliott, RadioConfig, SikRadio, Timing, parse_radio
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.cli import main
from gcs_planner.errors import LinkError
from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.pacing import RadioFlow, Window
from gcs_planner.link.protocol import mission_differences
from gcs_planner.mission.items import MissionItem

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

SCENARIO = "missions/example/scenario.toml"


def _mission(n: int) -> list[MissionItem]:
    return [
        MissionItem(i, 0, 16, x=305_000_000 + 97 * i, y=1_235_000_000 + 89 * i, z=500.0 + i % 7)
        for i in range(n)
    ]


@contextmanager
def _over_radio(
    flavour: str = "ardupilot", capacity: int = 1000, **radio: object
) -> Iterator[tuple[MockVehicle, SikRadio, MissionClient]]:
    """A mock vehicle behind a SiK pair, and a connected client on the ground side."""
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour, capacity=capacity) as vehicle:
        cfg = RadioConfig(**radio)  # type: ignore[arg-type]
        with SikRadio("udpin:127.0.0.1:0", f"udpout:127.0.0.1:{port}", cfg) as r:
            link = open_link(r.ground_connection)
            try:
                # The mission protocol over the radio (MAVFTP's tests: tests/test_ftp.py).
                client = MissionClient(link, transfer="mission")
                client.connect(timeout=30.0)
                yield vehicle, r, client
            finally:
                link.close()


def _holds(vehicle: MockVehicle, items: list[MissionItem]) -> bool:
    return not mission_differences(items, vehicle.mission, skip_home=vehicle.flavour == "ardupilot")


# The radio on its own --------------------------------------------------------------------------
def test_timing_is_sik_tdm_at_64_kbit():
    # tdm_init at AIR_SPEED 64: 9 ticks of 16 us a byte, 130-tick latency, windows of three
    # 248-byte packets (7,086 ticks), silences of two latencies.
    t = Timing.of(RadioConfig(air_rate=64))
    assert t.byte_s == pytest.approx(9 * 16e-6)
    assert t.latency_s == pytest.approx(130 * 16e-6)
    assert t.window_s == pytest.approx(7086 * 16e-6)
    assert t.silence_s == pytest.approx(260 * 16e-6)
    assert t.max_data == 248
    fast = Timing.of(RadioConfig(air_rate=250))
    assert fast.window_s < t.window_s and fast.byte_s < t.byte_s


def test_gilbert_elliott_has_the_mean_loss_and_bursts_asked_for():
    ge = GilbertElliott(loss=0.05, burst=4.0, seed=3)
    draws = [ge.lost() for _ in range(200_000)]
    assert sum(draws) / len(draws) == pytest.approx(0.05, abs=0.01)
    bursts, run = [], 0
    for lost in draws:
        if lost:
            run += 1
        elif run:
            bursts.append(run)
            run = 0
    assert sum(bursts) / len(bursts) == pytest.approx(4.0, rel=0.15)
    again = GilbertElliott(loss=0.05, burst=4.0, seed=3)
    assert [again.lost() for _ in range(1000)] == draws[:1000]  # seeded


def test_radio_arguments_are_checked():
    assert parse_radio("sik") == 64 and parse_radio("SIK:250") == 250
    for bad in ("lora", "sik:fast", "sik:1000"):
        with pytest.raises(ValueError):
            parse_radio(bad)
    with pytest.raises(ValueError):
        RadioConfig(loss=1.0)


def test_a_flooded_radio_fills_drops_and_says_so_in_txbuf():
    """More than the air carries (16 kbit/s air under a 57,600-baud writer): the serial-in
    buffer fills, frames are dropped, and the RADIO_STATUS for a heartbeat says how full."""
    mav = mavlink.MAVLink(None, 255, 190)
    heartbeat = bytes(mav.heartbeat_encode(6, 8, 0, 0, 4).pack(mav))
    item = bytes(
        mav.mission_item_int_encode(1, 1, 0, 3, 16, 0, 1, 0, 0, 0, 0, 1, 1, 5, 0).pack(mav)
    )
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(("127.0.0.1", 0))
    gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    gcs.bind(("127.0.0.1", 0))
    gcs.settimeout(0.2)
    cfg = RadioConfig(air_rate=16)
    lowest = 101
    try:
        with SikRadio("udpin:127.0.0.1:0", f"udpout:127.0.0.1:{sink.getsockname()[1]}", cfg) as r:
            target = r.ground_address
            for _ in range(300):
                gcs.sendto(item, target)
            deadline = time.monotonic() + 60.0
            while time.monotonic() < deadline and not (r.counts.serial_in_drops and lowest <= 10):
                # SiK reports when the heartbeat goes to the air (check_heartbeat in
                # mavlink_frame): what was written after it is what fills the buffer then.
                gcs.sendto(heartbeat, target)
                for _ in range(10):
                    gcs.sendto(item, target)
                try:
                    data = gcs.recv(4096)
                except TimeoutError:
                    continue
                for m in mav.parse_buffer(data) or []:
                    if m.get_type() == "RADIO_STATUS":
                        assert (m.get_srcSystem(), m.get_srcComponent()) == (51, 68)
                        lowest = min(lowest, m.txbuf)
            assert r.counts.serial_in_drops > 0
            assert lowest <= 10
    finally:
        sink.close()
        gcs.close()


def test_radio_status_reaches_the_client_and_ardupilot_reads_it_as_ardupilot_does():
    flow = RadioFlow()
    mav = mavlink.MAVLink(None, 51, 68)
    for txbuf in (10, 10, 40):
        flow.observe(mav.radio_status_encode(200, 190, txbuf, 40, 40, 0, 0))
    assert flow.congested() is False  # 40 % free is above the 33 % gate
    assert flow.slowdown_s == pytest.approx(0.060 + 0.060 + 0.020)
    flow.observe(mav.radio_status_encode(200, 190, 33, 40, 40, 0, 0))
    assert flow.congested()
    flow.at -= 10.0  # a stale report is no radio (last_txbuf_is_greater)
    assert not flow.congested() and flow.extra_wait() == 0.0


def test_the_download_window_follows_delivery_rate_times_round_trip():
    w = Window(start=4, low=2, high=32)
    for i in range(30):  # 20 answers a second, 0.5 s median round trip: 10 in flight
        w.rtt(0.5 + (i % 3 - 1) * 0.1)
        w.delivered(i * 0.05)
    assert w.size == 14  # ceil(1.25 * 10) + 1
    for i in range(30):  # a fast link never goes past the ceiling
        w.rtt(0.5)
        w.delivered(2.0 + i * 0.001)
    assert w.size == 32


# Transfers through it --------------------------------------------------------------------------
@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_upload_and_read_back_over_a_lossy_radio(flavour):
    items = _mission(30)
    with _over_radio(flavour, loss=0.05, burst=4.0, seed=11) as (vehicle, r, client):
        report = client.upload_verified(items)
        assert report.items == 30
        assert _holds(vehicle, items)
        assert client.radio.reports > 0  # the ground radio's RADIO_STATUS were read
        assert r.counts.statuses > 0


def test_download_over_a_lossy_radio_is_the_vehicles_mission():
    items = _mission(120)
    with _over_radio(loss=0.05, burst=4.0, seed=5) as (vehicle, r, client):
        vehicle.missions.commit(items)
        got = client.download()
        assert [(it.x, it.y, it.z) for it in got[1:]] == [(it.x, it.y, it.z) for it in items[1:]]
        assert client.window_used > 2  # the window opened to the link
        # A resend per frame lost, or per answer that came after all (the client counts the
        # answers to an item it already held), later than a round-trip timeout through which
        # nothing came: a machine that keeps the radio's or the vehicle's thread off the CPU
        # makes answers late, not the client hasty.
        assert client.retry_count <= r.counts.broken_frames + client.late_answers + 5
        # Nothing asked twice while its answer could still come: no late answer is to a
        # request asked again while one asked before it was unanswered (on this in-order link
        # its answer was queued behind that one's), however slow the machine.
        assert client.hasty_resends == 0


def _fade_when(condition, radio: SikRadio, seconds: float, done: threading.Event) -> None:
    deadline = time.monotonic() + 300.0
    while time.monotonic() < deadline and not done.is_set():
        if condition():
            radio.fade(seconds)
            done.set()
            return
        time.sleep(0.01)


def test_a_5_s_fade_in_the_middle_of_an_upload_is_survived():
    # 24 items, the fade from the 10th: the fade is what is survived (a client that gives up
    # after 2 s of silence fails here), the items around it only the way in and out.
    items = _mission(24)
    with _over_radio(loss=0.02, seed=2) as (vehicle, r, client):
        faded = threading.Event()

        def halfway() -> bool:
            up = vehicle.missions.upload
            return up is not None and len(up.items) >= 10

        watcher = threading.Thread(target=_fade_when, args=(halfway, r, 5.0, faded), daemon=True)
        watcher.start()
        report = client.upload_verified(items)
        watcher.join(timeout=5.0)
        assert faded.is_set()
        assert report.items == 24 and _holds(vehicle, items)
        # The fade was survived by resending, not by a flood of copies.
        assert 0 < report.retries < 40


def test_a_5_s_fade_in_the_middle_of_the_read_back_is_survived():
    # 24 items: the upload before it, one TDM round an item, is only the way to a read-back
    # long enough for the fade to fall in its middle.
    items = _mission(24)
    with _over_radio(loss=0.0, seed=4) as (vehicle, r, client):
        faded = threading.Event()
        lost_before = r.counts.packets_lost
        committed: list[int] = []  # frames sent to the ground when the upload was stored

        def stored() -> bool:  # the upload has just been committed: the read-back starts
            return len(vehicle.mission) == len(items)

        # The fade starts a little into the read-back, not before it: once the vehicle has
        # sent ten frames more (its ACK, then items read back) since it stored the mission.
        def later() -> bool:
            if not committed:
                if stored() and vehicle.acks_sent:
                    committed.append(r.counts.frames_to_ground)
                return False
            return r.counts.frames_to_ground >= committed[0] + 10

        watcher = threading.Thread(target=_fade_when, args=(later, r, 5.0, faded), daemon=True)
        watcher.start()
        report = client.upload_verified(items)
        faded_during = faded.is_set()  # the fade began before the read-back ended
        watcher.join(timeout=5.0)
        assert faded_during and r.counts.packets_lost > lost_before
        assert report.items == 24 and _holds(vehicle, items)


# The read-back decides when the end of the upload is uncertain ---------------------------------
def _drop_first_accepted(vehicle: MockVehicle) -> list[int]:
    """Make the vehicle's first MISSION_ACK ACCEPTED never leave it (lost on the link)."""
    dropped: list[int] = []
    real = vehicle.missions.ack

    def ack(peer, result, mission_type=0):
        if result == mavlink.MAV_MISSION_ACCEPTED and not dropped:
            dropped.append(result)
            vehicle.missions.acks_sent.append(result)
            return
        real(peer, result, mission_type)

    vehicle.missions.ack = ack  # type: ignore[method-assign]
    return dropped


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_a_lost_final_ack_is_settled_by_the_read_back(flavour):
    items = _mission(12)
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour) as vehicle:
        dropped = _drop_first_accepted(vehicle)
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, transfer="mission")  # its MISSION_ACKs are the test
            client.connect(timeout=10.0)
            report = client.upload_verified(items)
        finally:
            link.close()
        assert dropped and _holds(vehicle, items)
        # ArduPilot answers the resent last item with MAV_MISSION_ERROR (no longer receiving):
        # the read-back, not that answer, says the mission is there. PX4 acknowledges again.
        assert report.unacknowledged == (flavour == "ardupilot")
        if flavour == "ardupilot":
            assert mavlink.MAV_MISSION_ERROR in vehicle.acks_sent


def test_an_unacknowledged_upload_the_vehicle_did_not_store_is_never_a_success():
    items = _mission(12)
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="ardupilot") as vehicle:
        _drop_first_accepted(vehicle)
        vehicle.missions.commit = lambda got: None  # type: ignore[method-assign]
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, transfer="mission")  # its MISSION_ACKs are the test
            client.connect(timeout=10.0)
            with pytest.raises(LinkError, match="differs") as err:
                client.upload_verified(items)
        finally:
            link.close()
        assert "never acknowledged" not in str(err.value)  # it was read back: it differs
        assert "every item was sent" in str(err.value)


# From the command line -------------------------------------------------------------------------
def test_mock_vehicle_refuses_a_radio_on_a_serial_connection(capsys):
    assert main(["mock-vehicle", "--connect", "/dev/ttyUSB9", "--scenario", SCENARIO,
                 "--radio", "sik"]) == 2  # fmt: skip
    assert "--radio" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["mock-vehicle", "--connect", "udpin:127.0.0.1:1", "--scenario", SCENARIO,
              "--radio", "lora"])  # fmt: skip
    assert exc.value.code == 2


def test_upload_and_download_through_mock_vehicle_radio_process(tmp_path, capsys):
    """`gcs-planner mock-vehicle --radio sik:250` in one process, `upload` / `download` in
    this one, as a user would run them from two terminals."""
    import json
    import signal
    import subprocess
    import sys

    from gcs_planner.mission.waypoints import dumps_items

    port = free_udp_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "gcs_planner", "mock-vehicle", "--connect",
         f"udpin:127.0.0.1:{port}", "--scenario", SCENARIO, "--radio", "sik:250",
         "--radio-loss", "0.05", "--seed", "3"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )  # fmt: skip
    try:
        items = [
            MissionItem(i, 0, 16, param2=30.0, x=305_000_000 + 500 * i, y=1_235_000_000, z=120.0)
            for i in range(15)
        ]
        wp = tmp_path / "m.waypoints"
        wp.write_text(dumps_items(items, "ardupilot", (30.5, 123.5, 0.0)))
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet", "--wait", "60"]
        assert main(["upload", str(wp), *conn, "--keep-loiter-radius"]) == 0
        assert "uploaded and verified 15 items" in capsys.readouterr().out
        out = tmp_path / "back.json"
        assert main(["download", *conn, "--out", str(out)]) == 0
        back = json.loads(out.read_text())["items"]
        assert [row["x"] for row in back[1:]] == [it.x for it in items[1:]]
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            err = proc.communicate(timeout=30)[1]
        except subprocess.TimeoutExpired:
            proc.kill()
            err = proc.communicate()[1]
    assert proc.returncode == 0, err
    assert "SiK radio pair at 250 kbit/s" in err and "holds 15 items" in err


def test_mock_vehicle_radio_reached_by_a_listening_ground_station_takes_500_items(tmp_path, capsys):
    """Issue 51: `mock-vehicle --radio sik --connect udpout:...` (the ground station listens,
    README's usual pairing) sent nothing: the vehicle listened behind the air radio too, and
    nobody spoke first. 500 items through the 64 kbit/s pair at 5 % burst loss, by MAVFTP as
    the client chooses for ArduPilot (seconds; the mission protocol takes minutes for that
    many over this radio), then 20 more by the mission protocol."""
    import signal
    import subprocess
    import sys

    from gcs_planner.mission.waypoints import dumps_items

    port = free_udp_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "gcs_planner", "mock-vehicle", "--connect",
         f"udpout:127.0.0.1:{port}", "--scenario", SCENARIO, "--radio", "sik",
         "--radio-loss", "0.05", "--seed", "3"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )  # fmt: skip
    try:
        conn = ["--connect", f"udpin:127.0.0.1:{port}", "--quiet", "--wait", "60"]
        for n, transfer, way in ((500, "auto", "by MAVFTP"), (20, "mission", "")):
            items = [MissionItem(i, 0, 16, param2=30.0, x=305_000_000 + 500 * i,
                                 y=1_235_000_000, z=120.0) for i in range(n)]  # fmt: skip
            wp = tmp_path / f"m{n}.waypoints"
            wp.write_text(dumps_items(items, "ardupilot", (30.5, 123.5, 0.0)))
            args = ["upload", str(wp), *conn, "--keep-loiter-radius", "--transfer", transfer]
            assert main(args) == 0
            out = capsys.readouterr().out
            assert f"uploaded and verified {n} items" in out and way in out
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            err = proc.communicate(timeout=30)[1]
        except subprocess.TimeoutExpired:
            proc.kill()
            err = proc.communicate()[1]
    assert proc.returncode == 0, err
    assert "SiK radio pair at 64 kbit/s" in err and "holds 20 items" in err
