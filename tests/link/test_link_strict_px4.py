"""The client against a vehicle that keeps PX4's mission rules (support/strict_px4.py, written from
``MavlinkMissionManager`` in mavlink_mission.cpp): downloads and verified uploads through 20 %
frame loss each way, a MISSION_ACK error in the middle of a download, and a vehicle without
MISSION_REQUEST_INT.

No test asserts wall-clock time; what is compared is what the vehicle stored and counted."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from support.strict_px4 import SENDLIST, StrictPx4

from gcs_planner.errors import LinkError
from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.mission.items import MissionItem

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits


def _mission(n: int) -> list[MissionItem]:
    return [
        MissionItem(i, 3, 16, x=305_000_000 + 97 * i, y=1_235_000_000 + 89 * i, z=500.0 + i % 7)
        for i in range(n)
    ]


def _places(items: list[MissionItem]) -> list[tuple[int, int, float]]:
    return [(int(it.x), int(it.y), float(it.z)) for it in items]


@contextmanager
def _client(vehicle: StrictPx4, **kw: Any) -> Iterator[MissionClient]:
    link = open_link(f"udpout:127.0.0.1:{vehicle.port}")
    try:
        client = MissionClient(link, **kw)
        client.connect(timeout=20.0)
        yield client
    finally:
        link.close()


@pytest.mark.parametrize("seed", range(10))
def test_px4_at_20_percent_loss_takes_every_upload_and_download(seed):
    """Issue 51: with several requests out, one lost request made PX4 end the download (MISSION_ACK
    ERROR): 6 of 6 downloads refused and 6 of 6 verified uploads false-failed at 5-20 % loss."""
    # 30 items: with the window of the other autopilots (several requests out) every one of
    # these ten seeds ends in a refused read-back (six MISSION_ACK ERRORs or a stall).
    items = _mission(30)
    # The client's protocol timeout at 0.5 s (1.5 s by default): what it bounds here are the
    # waits for a first answer after a frame lost, not what the test is about. Its stall limit,
    # nine of them (4.5 s), stays under PX4's 5 s operation timeout, the stricter for false
    # failures; with six (3 s) a busy CI machine once missed every answer to a request list.
    with (
        StrictPx4(loss=0.2, seed=seed) as vehicle,
        _client(vehicle, timeout=0.5, retries=8) as client,
    ):
        assert client.requests_in_sequence()  # the record's trait: PX4 serves in sequence
        report = client.upload_verified(items)
        assert report.items == 30 and _places(vehicle.mission) == _places(items)
        got = client.download()
        assert _places(got) == _places(items)
        # One request out at a time: never one PX4 takes for out of sequence.
        assert vehicle.ended_downloads == 0 and client.window_used == 1


class _EndsOnce(StrictPx4):
    """Ends the download once at item ``at`` as PX4 ends one asked out of sequence."""

    def __init__(self, at: int, times: int = 1, **kw: Any) -> None:
        super().__init__(**kw)
        self.at, self.times = at, times

    def _request(self, msg: Any, sender: tuple[int, int], now: float) -> None:
        if self.state == SENDLIST and int(msg.seq) == self.at and self.times > 0:
            self.times -= 1
            self.state = "idle"
            self.ended_downloads += 1
            self._ack(sender, mavlink.MAV_MISSION_ERROR)
            return
        super()._request(msg, sender, now)


def test_an_error_ack_in_the_middle_of_a_download_starts_it_again():
    items = _mission(60)
    with _EndsOnce(at=40) as vehicle, _client(vehicle) as client:
        vehicle.mission = list(items)
        assert _places(client.download()) == _places(items)
        assert vehicle.ended_downloads == 1 and client.retry_count >= 1


def test_an_error_ack_in_the_middle_of_the_read_back_is_not_let_pass():
    """The read-back took MAV_MISSION_ERROR for a leftover of the upload and waited out its
    stall limit (30-43 s) on a PX4 that had gone idle."""
    items = _mission(60)
    with _EndsOnce(at=30) as vehicle, _client(vehicle, timeout=0.5, retries=2) as client:
        report = client.upload_verified(items)
        assert report.items == 60 and _places(vehicle.mission) == _places(items)
        assert vehicle.ended_downloads == 1


def test_a_vehicle_that_ends_every_download_is_a_clear_error():
    with _EndsOnce(at=5, times=100) as vehicle, _client(vehicle, retries=2) as client:
        vehicle.mission = _mission(20)
        with pytest.raises(LinkError, match="ended it 3 times.*MAV_MISSION_ERROR"):
            client.download()
        assert vehicle.ended_downloads == 3


class _NoRequestInt(StrictPx4):
    """A vehicle that knows only the float MISSION_REQUEST: MISSION_REQUEST_INT is answered
    MAV_MISSION_UNSUPPORTED."""

    def _request(self, msg: Any, sender: tuple[int, int], now: float) -> None:
        if msg.get_type() == "MISSION_REQUEST_INT":
            self.unsupported = getattr(self, "unsupported", 0) + 1
            self._ack(sender, mavlink.MAV_MISSION_UNSUPPORTED)
            return
        super()._request(msg, sender, now)


def test_request_int_answered_unsupported_falls_back_to_mission_request():
    items = _mission(12)
    with _NoRequestInt() as vehicle, _client(vehicle) as client:
        vehicle.mission = list(items)
        got = client.download()
    assert vehicle.unsupported == 1  # asked once, then the older request
    # MISSION_ITEM carries degrees in float32: within half its step at 123.5 deg (76 degE7).
    for g, it in zip(got, items, strict=True):
        assert abs(g.x - it.x) <= 38 and abs(g.y - it.y) <= 38 and g.z == it.z
