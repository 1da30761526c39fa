"""The mock vehicle's PX4 flavour rule by rule, as PX4's mission manager keeps them
(``MavlinkMissionManager``, src/modules/mavlink/mavlink_mission.cpp); one script of exchanges
answered alike by the mock and by support/strict_px4.py, the small vehicle written independently
from the same source; and the client's transfers through the mock at 20 % frame loss.

Driven by a raw pymavlink peer over UDP on 127.0.0.1. An absence ("nothing answered") is
checked by a round trip the vehicle answers only after handling what came before it (one socket,
in order), never by waiting out a time; no test asserts wall-clock time."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from gcs_planner.sim.faults import FaultRates
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from support import strict_px4

from gcs_planner.aircraft.autopilot import PX4
from gcs_planner.link.connection import Link, mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import item_to_message
from gcs_planner.mission.items import MissionItem

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

FLAVOUR = PX4.firmware
ITEMS = [MissionItem(i, 3, 16, x=305_000_000 + 97 * i, y=1_235_000_000, z=100.0) for i in range(4)]
WAIT_S = 10.0  # generous: an event-driven wait, not a time window
MISSION_ANSWERS = frozenset(
    {"MISSION_COUNT", "MISSION_ITEM", "MISSION_ITEM_INT", "MISSION_REQUEST", "MISSION_REQUEST_INT",
     "MISSION_ACK"}
)  # fmt: skip


@contextmanager
def px4_and_peer(**kw: Any) -> Iterator[tuple[MockVehicle, Link]]:
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=FLAVOUR, **kw) as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            link.send(link.mav.heartbeat_encode(6, 8, 0, 0, 4))
            yield vehicle, link
        finally:
            link.close()


def answers_until(link: Link, last: Callable[[Any], bool]) -> list[Any]:
    """The mission messages the vehicle sends up to and including the first that ``last``
    accepts."""
    out: list[Any] = []
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        msg = link.recv(0.05)
        if msg is None or msg.get_type() not in MISSION_ANSWERS | {"PARAM_VALUE"}:
            continue
        out.append(msg)
        if last(msg):
            return out
    raise AssertionError(f"no end of the answers came; got {[m.get_type() for m in out]}")


def answered_before_round_trip(link: Link) -> list[Any]:
    """The mission messages the vehicle sent before it answered a PARAM_REQUEST_READ sent now:
    what it answered to everything sent before."""
    link.send(link.mav.param_request_read_encode(1, 1, b"", 0))
    got = answers_until(link, lambda m: m.get_type() == "PARAM_VALUE")
    return [m for m in got if m.get_type() != "PARAM_VALUE"]


def of(kind: str, **fields: int) -> Callable[[Any], bool]:
    return lambda m: m.get_type() == kind and all(getattr(m, k) == v for k, v in fields.items())


def start_download(vehicle: MockVehicle, link: Link) -> None:
    vehicle.missions.commit(ITEMS)
    link.send(link.mav.mission_request_list_encode(1, 1, 0))
    answers_until(link, of("MISSION_COUNT", count=len(ITEMS)))


def request(link: Link, seq: int) -> None:
    link.send(link.mav.mission_request_int_encode(1, 1, seq, 0))


# handle_mission_request_both ------------------------------------------------------------------
def test_a_download_request_out_of_sequence_ends_it_with_mission_error():
    """Only the next item or the last one again is answered; any other request switches to idle
    and answers MISSION_ACK MAV_MISSION_ERROR ("REJ. CMD: Req. WP was unexpected"); later
    requests are ignored, idle."""
    with px4_and_peer(request_timeout=30.0) as (vehicle, link):
        start_download(vehicle, link)
        request(link, 0)
        answers_until(link, of("MISSION_ITEM_INT", seq=0))
        request(link, 2)  # item 1 skipped
        ack = answers_until(link, of("MISSION_ACK"))[-1]
        assert ack.type == mavlink.MAV_MISSION_ERROR
        request(link, 1)  # the transfer is over: nothing answers this
        assert answered_before_round_trip(link) == []
        assert vehicle.missions.download is None and vehicle.missions.downloads_ended == 1
        assert "WPM: REJ. CMD: Req. WP was unexpected" in vehicle.statustexts


def test_the_last_request_again_is_answered_again_and_the_list_goes_on():
    with px4_and_peer(request_timeout=30.0) as (vehicle, link):
        start_download(vehicle, link)
        for seq in (0, 0, 1, 1, 2, 3):
            request(link, seq)
        got = answered_before_round_trip(link)
        assert [(m.get_type(), m.seq) for m in got] == [
            ("MISSION_ITEM_INT", s) for s in (0, 0, 1, 1, 2, 3)
        ]
        link.send(link.mav.mission_ack_encode(1, 1, mavlink.MAV_MISSION_ACCEPTED, 0))
        assert answered_before_round_trip(link) == []
        assert vehicle.missions.download is None and vehicle.missions.downloads_ended == 0


def test_a_request_while_idle_is_ignored_without_a_word():
    """ "Silently ignore this as some OSDs have buggy mission protocol implementations"."""
    with px4_and_peer() as (vehicle, link):
        vehicle.missions.commit(ITEMS)
        request(link, 0)
        assert answered_before_round_trip(link) == []
        assert vehicle.missions.acks_sent == []


def test_a_download_heard_from_no_more_ends_after_the_operation_timeout():
    """``MavlinkMissionManager::send``: any transfer with nothing received for
    MAVLINK_MISSION_PROTOCOL_TIMEOUT_DEFAULT goes idle with "Operation timeout", no ACK."""
    with px4_and_peer(upload_timeout=0.3) as (vehicle, link):
        start_download(vehicle, link)
        deadline = time.monotonic() + WAIT_S
        while vehicle.missions.download is not None and time.monotonic() < deadline:
            time.sleep(0.02)
        assert vehicle.missions.download is None
        assert "Operation timeout" in vehicle.statustexts
        request(link, 0)  # idle now: ignored
        assert answered_before_round_trip(link) == []


# handle_mission_count, handle_mission_item_both ---------------------------------------------
def item(link: Link, seq: int) -> None:
    link.send(item_to_message(link.mav, ITEMS[seq], 1, 1))


def test_an_upload_item_out_of_sequence_is_ignored():
    """ "Item sequence not expected, ignore item": no answer, the item waited for is asked for."""
    with px4_and_peer(request_timeout=30.0) as (vehicle, link):
        link.send(link.mav.mission_count_encode(1, 1, 3, 0))
        answers_until(link, of("MISSION_REQUEST_INT", seq=0))
        item(link, 1)
        assert answered_before_round_trip(link) == []
        item(link, 0)
        answers_until(link, of("MISSION_REQUEST_INT", seq=1))
        assert vehicle.missions.acks_sent == []


def test_the_request_is_asked_again_a_quarter_second_after_the_last():
    """MAVLINK_MISSION_RETRY_TIMEOUT_DEFAULT (mavlink_mission.h): the record's 0.25 s is the
    mock's default, and the request does come again."""
    with px4_and_peer() as (vehicle, link):
        assert vehicle.missions.request_timeout == PX4.protocol.request_resend_s == 0.25
        assert vehicle.missions.upload_timeout == PX4.protocol.transfer_timeout_s == 5.0
        link.send(link.mav.mission_count_encode(1, 1, 3, 0))
        for _ in range(3):  # the first request, then two more with nothing sent
            answers_until(link, of("MISSION_REQUEST_INT", seq=0))


def test_mission_count_in_the_middle_of_an_upload():
    """The partner's count again before item 0: item 0 asked for again, the count not read again
    ("looks like our MISSION_REQUEST was lost"); after item 0: MAV_MISSION_ERROR ("busy");
    another ground station's: MAV_MISSION_ERROR; during a download: MAV_MISSION_ERROR."""
    with px4_and_peer(request_timeout=30.0) as (vehicle, link):
        other = open_link(link.connection, source_system=254, source_component=190)
        try:
            link.send(link.mav.mission_count_encode(1, 1, 3, 0))
            answers_until(link, of("MISSION_REQUEST_INT", seq=0))
            link.send(link.mav.mission_count_encode(1, 1, 2, 0))  # again, and shorter
            answers_until(link, of("MISSION_REQUEST_INT", seq=0))
            item(link, 0)
            answers_until(link, of("MISSION_REQUEST_INT", seq=1))
            link.send(link.mav.mission_count_encode(1, 1, 3, 0))
            assert answers_until(link, of("MISSION_ACK"))[-1].type == mavlink.MAV_MISSION_ERROR
            other.send(other.mav.mission_count_encode(1, 1, 3, 0))
            assert answers_until(other, of("MISSION_ACK"))[-1].type == mavlink.MAV_MISSION_ERROR
            item(link, 1)
            answers_until(link, of("MISSION_REQUEST_INT", seq=2))  # the first count holds
            item(link, 2)
            ack = answers_until(link, of("MISSION_ACK"))[-1]
            assert ack.type == mavlink.MAV_MISSION_ACCEPTED
            assert vehicle.mission == ITEMS[:3]
            link.send(link.mav.mission_request_list_encode(1, 1, 0))
            answers_until(link, of("MISSION_COUNT", count=3))
            link.send(link.mav.mission_count_encode(1, 1, 1, 0))  # while sending the list
            assert answers_until(link, of("MISSION_ACK"))[-1].type == mavlink.MAV_MISSION_ERROR
        finally:
            other.close()


# The same script against the strict vehicle ---------------------------------------------------
def _script(mav: Any) -> list[Any]:
    """An exchange that visits each rule: a download with a repeat and a request out of
    sequence, an upload refused during a list, a list ended by its ACK, an upload with its
    count again, an item out of sequence, a busy count, a list asked while receiving, the last
    item again, a stale item, a clear."""
    msgs = [
        mav.mission_request_list_encode(1, 1, 0),
        mav.mission_request_int_encode(1, 1, 0, 0),
        mav.mission_request_int_encode(1, 1, 0, 0),
        mav.mission_request_int_encode(1, 1, 1, 0),
        mav.mission_request_int_encode(1, 1, 3, 0),
        mav.mission_request_int_encode(1, 1, 2, 0),
        mav.mission_request_list_encode(1, 1, 0),
        mav.mission_count_encode(1, 1, 3, 0),
        mav.mission_ack_encode(1, 1, mavlink.MAV_MISSION_ACCEPTED, 0),
        mav.mission_count_encode(1, 1, 3, 0),
        mav.mission_count_encode(1, 1, 3, 0),
    ]
    up = [item_to_message(mav, ITEMS[s], 1, 1) for s in range(3)]
    msgs += [up[1], up[0], mav.mission_count_encode(1, 1, 3, 0)]
    msgs += [mav.mission_request_list_encode(1, 1, 0), up[1], up[2], up[2], up[0]]
    msgs += [mav.mission_clear_all_encode(1, 1, 0), mav.mission_request_list_encode(1, 1, 0)]
    return msgs


def _summary(msg: Any) -> tuple[str, int]:
    kind = msg.get_type()
    if kind == "MISSION_ACK":
        return kind, int(msg.type)
    if kind == "MISSION_COUNT":
        return kind, int(msg.count)
    return kind, int(msg.seq)


def _run_script(link: Link) -> list[tuple[str, int]]:
    for msg in _script(link.mav):
        link.send(msg)
    got = answers_until(link, lambda m: m.get_type() == "MISSION_COUNT" and m.count == 0)
    return [_summary(m) for m in got]


def test_the_mock_and_the_strict_vehicle_answer_one_script_alike(monkeypatch):
    """Two vehicles written from mavlink_mission.cpp apart, one check of the other: with the
    timers out of the way (no resend, no timeout) the same messages get the same answers."""
    monkeypatch.setattr(strict_px4, "RETRY_S", 60.0)
    monkeypatch.setattr(strict_px4, "PROTOCOL_TIMEOUT_S", 60.0)
    with strict_px4.StrictPx4() as strict:
        strict.mission = list(ITEMS)
        link = open_link(f"udpout:127.0.0.1:{strict.port}")
        try:
            by_strict = _run_script(link)
        finally:
            link.close()
    with px4_and_peer(request_timeout=60.0, upload_timeout=60.0) as (vehicle, link):
        vehicle.missions.commit(ITEMS)
        by_mock = _run_script(link)
    error, accepted = mavlink.MAV_MISSION_ERROR, mavlink.MAV_MISSION_ACCEPTED
    assert by_strict == [
        ("MISSION_COUNT", 4), ("MISSION_ITEM_INT", 0), ("MISSION_ITEM_INT", 0),
        ("MISSION_ITEM_INT", 1), ("MISSION_ACK", error), ("MISSION_COUNT", 4),
        ("MISSION_ACK", error), ("MISSION_REQUEST_INT", 0), ("MISSION_REQUEST_INT", 0),
        ("MISSION_REQUEST_INT", 1), ("MISSION_ACK", error), ("MISSION_REQUEST_INT", 2),
        ("MISSION_ACK", accepted), ("MISSION_ACK", accepted), ("MISSION_ACK", error),
        ("MISSION_ACK", accepted), ("MISSION_COUNT", 0),
    ]  # fmt: skip
    assert by_mock == by_strict


# The client through it -----------------------------------------------------------------------
def _places(items: list[MissionItem]) -> list[tuple[int, int, float]]:
    return [(int(it.x), int(it.y), float(it.z)) for it in items]


@pytest.mark.parametrize("seed", range(4))
def test_100_items_up_and_down_at_20_percent_loss(seed):
    """Issue 51's done-when against the mock's PX4 flavour: 20 % of the frames lost each way,
    every upload verified and every download whole, no list ended by a request out of
    sequence."""
    items = [
        MissionItem(i, 3, 16, x=305_000_000 + 97 * i, y=1_235_000_000 + 89 * i, z=500.0 + i % 7)
        for i in range(100)
    ]
    loss = FaultRates(drop=0.2)
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=FLAVOUR, faults_out=loss, faults_in=loss,
                     fault_seed=seed) as vehicle:  # fmt: skip
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            # Ten retries, not the specification's five: at 20 % loss each way a request goes
            # unanswered six times in a row about once in 500 (0.36 ** 6), and which frames the
            # seed drops moves with the resends' timing on a busy machine (one CI run beside other
            # work lost a request list so). What is tested is the sequence, not the retry count.
            client = MissionClient(link, retries=10)
            client.connect(timeout=20.0)
            assert client.requests_in_sequence()
            report = client.upload_verified(items)
            assert report.items == 100 and _places(vehicle.mission) == _places(items)
            assert _places(client.download()) == _places(items)
        finally:
            link.close()
        assert vehicle.missions.downloads_ended == 0 and client.window_used == 1
