"""MAVFTP on a link whose radio does not report its buffer (no RADIO_STATUS): the window halves
at a resend and grows back on clean answers, the resend timer backs off per resend in a row,
and over the emulated SiK radio with its reports switched off an upload neither floods the
radio's buffer nor resends more than the loss needs.

Counts, not clocks: what is compared is what the radio and the client counted."""

from __future__ import annotations

import pytest
from gcs_planner.sim.radio import RadioConfig, SikRadio
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.ftp import FtpClient
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.pacing import Backoff
from gcs_planner.link.protocol import mission_differences
from gcs_planner.mission.items import MissionItem

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits


def _mission(n: int) -> list[MissionItem]:
    return [
        MissionItem(i, 0, 16, x=305_000_000 + 97 * i, y=1_235_000_000 + 89 * i, z=500.0 + i % 7)
        for i in range(n)
    ]


def test_the_window_halves_once_per_loss_event_and_grows_one_per_window():
    b = Backoff(8, high=16)
    b.resent(10.0, round_trip=0.5)
    assert b.slots == 4 and b.halvings == 1
    b.resent(10.2, round_trip=0.5)  # the same burst: within a round trip of the last cut
    assert b.slots == 4 and b.halvings == 1
    b.resent(10.6, round_trip=0.5)
    assert b.slots == 2 and b.halvings == 2
    b.answered()
    b.answered()
    assert b.slots == 2  # 2 + 1/2 + 1/2.5: not yet a whole one more
    b.answered()
    assert b.slots == 3  # about a window of clean answers: one more
    for k in range(10):
        b.resent(100.0 + k, round_trip=0.5)
    assert b.slots == 1  # never below one request
    for _ in range(1000):
        b.answered()
    assert b.slots == 16  # never above the ceiling


def _client(reports: bool) -> FtpClient:
    mav = mavlink.MAVLink(None, 255, 190)
    return FtpClient(
        mav, lambda m: None, lambda t: None, (1, 1), radio_reports=lambda: reports, timeout=10.0
    )


def test_without_radio_reports_the_resend_timer_doubles_from_the_first_resend():
    quiet, reported = _client(False), _client(True)
    first = quiet.resend_wait(0)
    assert reported.resend_wait(0) == first
    assert quiet.resend_wait(1) == 2 * first and quiet.resend_wait(2) == 4 * first
    # A radio that reports its buffer: the first four go at the round trip's pace.
    assert [reported.resend_wait(k) for k in range(5)] == [first] * 5
    assert quiet.resend_wait(20) == reported.resend_wait(20) == 10.0  # the protocol timeout


def test_ftp_over_a_radio_without_radio_status_backs_off_and_resends_only_what_was_lost():
    # Air slower than the serial line and a small serial-in buffer (600 bytes: two 260-byte
    # WriteFile frames): what the client writes faster than the air takes is dropped by the
    # radio, and no RADIO_STATUS says so. A fixed window of six writes overflowed it 11 to 13
    # times in this upload over four seeds; backing off at each resend keeps it to a few.
    items = _mission(200)
    cfg = RadioConfig(air_rate=16, serial_in_bytes=600, status=False, loss=0.05, seed=3)
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", capacity=1000) as vehicle:
        with SikRadio("udpin:127.0.0.1:0", f"udpout:127.0.0.1:{port}", cfg) as r:
            link = open_link(r.ground_connection)
            try:
                client = MissionClient(link, transfer="ftp")
                client.connect(timeout=30.0)
                report = client.upload_verified(items)
            finally:
                link.close()
    assert report.transfer == "ftp" and report.verify == "crc"
    assert not mission_differences(items, vehicle.mission, skip_home=True)
    assert r.counts.statuses == 0 and client.radio.reports == 0  # no radio report at all
    lost = r.counts.broken_frames + r.counts.serial_in_drops + r.counts.serial_out_drops
    assert r.counts.packets_lost > 0  # the channel did lose packets
    # No more resends than frames were lost on the way (air or buffer), and few of those
    # lost to the buffer the client filled.
    assert client.retry_count <= lost
    assert r.counts.serial_in_drops <= 6
