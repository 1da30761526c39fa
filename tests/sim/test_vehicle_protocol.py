"""The mock vehicle as ArduPilot and PX4 are, and as a vehicle that no packet can kill: each
finding of issue 14 on the vehicle side, driven by a raw pymavlink peer over UDP on 127.0.0.1."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.link.connection import Link, mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import item_to_message
from gcs_planner.mission.items import MissionItem

ITEMS = [MissionItem(i, 0, 16, x=305_000_000 + 10 * i, y=1_235_000_000, z=100.0) for i in range(4)]
PROOF_S = 10.0  # generous: an event-driven wait, not a time window


def wait_for(link: Link, pred: Callable[[Any], bool], timeout: float = PROOF_S) -> Any | None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = link.recv(0.05)
        if msg is not None and pred(msg):
            return msg
    return None


def of(kind: str) -> Callable[[Any], bool]:
    return lambda m: m.get_type() == kind


@contextmanager
def vehicle_and_peer(
    flavour: str = "ardupilot", source_system: int = 255, **kw: Any
) -> Iterator[tuple[MockVehicle, Link]]:
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour, **kw) as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}", source_system=source_system)
        try:
            link.send(link.mav.heartbeat_encode(6, 8, 0, 0, 4))
            assert wait_for(link, of("HEARTBEAT")) is not None
            yield vehicle, link
        finally:
            link.close()


def still_answers(link: Link) -> bool:
    """A round trip the vehicle only completes if its loop is alive."""
    link.send(link.mav.param_request_read_encode(1, 1, b"", 0))
    return wait_for(link, of("PARAM_VALUE")) is not None


def upload_raw(link: Link, items: list[MissionItem]) -> None:
    client = MissionClient(link, target_system=1, target_component=1)
    client.upload(items)


# One packet must not kill the vehicle -----------------------------------------------------------
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 1e30, 2.5, -1.0])
def test_set_mission_current_with_a_bad_index_is_denied_not_fatal(value):
    with vehicle_and_peer("px4") as (vehicle, link):
        upload_raw(link, ITEMS)
        link.send(
            link.mav.command_long_encode(
                1, 1, mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, 0, value, 0, 0, 0, 0, 0, 0
            )
        )
        ack = wait_for(link, of("COMMAND_ACK"))
        assert ack is not None and ack.result == mavlink.MAV_RESULT_DENIED
        assert still_answers(link)
        assert vehicle.mission == ITEMS and vehicle.handler_errors == 0


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 1e12])
def test_param_set_of_a_non_number_is_refused_and_the_old_value_kept(flavour, value):
    if flavour == "px4" and math.isfinite(value):
        value = math.nan  # 1e12 fits PX4's float parameter; it only overflows an int16
    with vehicle_and_peer(flavour) as (vehicle, link):
        before = vehicle.parameters
        # WP_RADIUS is an int16 on ArduPilot; NAV_ACC_RAD a float on PX4.
        name, ptype = ("WP_RADIUS", 4) if flavour == "ardupilot" else ("NAV_ACC_RAD", 9)
        link.send(link.mav.param_set_encode(1, 1, name.encode(), value, ptype))
        got = wait_for(link, lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == name)
        assert got is not None and got.param_value == before[name]
        assert vehicle.parameters == before
        assert still_answers(link) and vehicle.handler_errors == 0


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_legacy_item_that_cannot_be_sent_back_is_refused_not_stored(flavour):
    with vehicle_and_peer(flavour) as (vehicle, link):
        upload_raw(link, ITEMS)
        link.send(link.mav.mission_count_encode(1, 1, 2, 0))
        assert wait_for(link, lambda m: m.get_type().startswith("MISSION_REQUEST")) is not None
        # MAV_CMD_DO_JUMP in MAV_FRAME_MISSION whose x = 3e5 does not fit MISSION_ITEM_INT.
        link.send(link.mav.mission_item_encode(1, 1, 0, 2, 177, 0, 1, 1, 2, 0, 0, 3e5, 0, 0, 0))
        ack = wait_for(link, of("MISSION_ACK"))
        assert ack is not None and ack.type == mavlink.MAV_MISSION_INVALID_PARAM5_X
        client = MissionClient(link, target_system=1, target_component=1)
        assert len(client.download()) == len(vehicle.mission)
        assert still_answers(link) and vehicle.handler_errors == 0


# ArduPilot as ArduPilot is ----------------------------------------------------------------------
def test_ardupilot_always_holds_home_at_seq_0():
    with vehicle_and_peer("ardupilot") as (vehicle, link):
        client = MissionClient(link, target_system=1, target_component=1, firmware="ardupilot")
        assert [it.command for it in client.download()] == [16]  # fresh: home alone
        client.upload(ITEMS)
        client.clear()
        assert len(vehicle.mission) == 1 and vehicle.mission[0].x == vehicle._home[0]
        client.upload_verified([])  # an empty upload leaves home, and verifies
        assert len(vehicle.mission) == 1


@pytest.mark.parametrize("flavour, request_kind", [("ardupilot", "MISSION_REQUEST"),
                                                   ("px4", "MISSION_REQUEST_INT")])  # fmt: skip
def test_items_are_requested_as_the_autopilot_requests_them(flavour, request_kind):
    with vehicle_and_peer(flavour) as (_vehicle, link):
        link.send(link.mav.mission_count_encode(1, 1, 2, 0))
        req = wait_for(link, lambda m: m.get_type().startswith("MISSION_REQUEST"))
        assert req is not None and req.get_type() == request_kind and req.seq == 0


def test_legacy_request_is_answered_with_the_legacy_item():
    with vehicle_and_peer("px4") as (_vehicle, link):
        upload_raw(link, ITEMS)
        # PX4 answers requests only inside a download it started (MISSION_REQUEST_LIST), in
        # sequence: the list, then items 0, 1, 2 asked the legacy way.
        link.send(link.mav.mission_request_list_encode(1, 1, 0))
        assert wait_for(link, of("MISSION_COUNT")) is not None
        for seq in range(3):
            link.send(link.mav.mission_request_encode(1, 1, seq, 0))
            item = wait_for(link, lambda m: m.get_type().startswith("MISSION_ITEM"))
            assert item is not None and item.get_type() == "MISSION_ITEM" and item.seq == seq
        assert abs(item.x - ITEMS[2].x / 1e7) < 1e-5


@pytest.mark.parametrize("mission_type, result, cleared", [
    (255, mavlink.MAV_MISSION_ACCEPTED, True),   # MAV_MISSION_TYPE_ALL
    (0, mavlink.MAV_MISSION_ACCEPTED, True),
    (1, mavlink.MAV_MISSION_ACCEPTED, False),    # the fence: the mission stays
    (2, mavlink.MAV_MISSION_ACCEPTED, False),    # rally points
    (7, mavlink.MAV_MISSION_UNSUPPORTED, False),  # no such type
])  # fmt: skip
def test_clear_all_per_mission_type(mission_type, result, cleared):
    with vehicle_and_peer("px4") as (vehicle, link):
        upload_raw(link, ITEMS)
        link.send(link.mav.mission_clear_all_encode(1, 1, mission_type))
        ack = wait_for(link, lambda m: m.get_type() == "MISSION_ACK")
        assert ack is not None and ack.type == result and ack.mission_type == mission_type
        assert vehicle.mission == ([] if cleared else ITEMS)


@pytest.mark.parametrize("kind", ["count", "list", "request"])
def test_unknown_mission_types_are_refused(kind):
    with vehicle_and_peer("px4") as (vehicle, link):
        upload_raw(link, ITEMS)
        mav = link.mav
        msg = {
            "count": mav.mission_count_encode(1, 1, 3, 9),
            "list": mav.mission_request_list_encode(1, 1, 9),
            "request": mav.mission_request_int_encode(1, 1, 0, 9),
        }[kind]
        link.send(msg)
        ack = wait_for(link, lambda m: m.get_type() in ("MISSION_ACK", "MISSION_COUNT"))
        assert ack is not None and ack.get_type() == "MISSION_ACK"
        assert ack.type == mavlink.MAV_MISSION_UNSUPPORTED
        assert vehicle.mission == ITEMS


def denied(msg: Any) -> bool:
    return msg.get_type() == "MISSION_ACK" and msg.type == mavlink.MAV_MISSION_DENIED


# Two ground stations -----------------------------------------------------------------------------
def statustext_seen(vehicle: MockVehicle, text: str, timeout: float = PROOF_S) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if any(text in t for t in vehicle.statustexts):
            return True
        time.sleep(0.02)
    return False


@pytest.mark.parametrize(
    "flavour, other_ids",
    # The same ids from another address restart an ArduPilot upload (it cannot tell them
    # apart: MissionItemProtocol::handle_mission_count), so that pair is PX4's alone.
    [("ardupilot", (254, 190)), ("px4", (254, 190)), ("px4", (255, 190))],
)
def test_a_second_ground_station_is_refused_during_a_transfer(flavour, other_ids):
    """Other ids, or the same ids from another address (a second `upload` process), are
    refused; the transfer in progress completes as sent. ArduPilot refuses with
    MAV_MISSION_DENIED (MissionItemProtocol::handle_mission_count / handle_mission_item); PX4
    answers another's MISSION_COUNT MAV_MISSION_ERROR and its items with a status text only
    (mavlink_mission.cpp: "partner id mismatch")."""
    quiet = autopilot_for(flavour).protocol.refuses_quietly
    refusal = mavlink.MAV_MISSION_ERROR if quiet else mavlink.MAV_MISSION_DENIED
    with vehicle_and_peer(flavour, request_timeout=30.0) as (vehicle, first):
        other = open_link(
            first.connection, source_system=other_ids[0], source_component=other_ids[1]
        )
        try:
            first.send(first.mav.mission_count_encode(1, 1, 2, 0))
            assert wait_for(first, lambda m: m.get_type().startswith("MISSION_REQUEST"))
            other.send(other.mav.mission_count_encode(1, 1, 3, 0))
            refused = wait_for(other, of("MISSION_ACK"))
            assert refused is not None and refused.type == refusal
            other.send(item_to_message(other.mav, ITEMS[3].with_seq(0), 1, 1))
            if quiet:
                assert statustext_seen(vehicle, "partner id mismatch")
            else:
                assert wait_for(other, denied) is not None
            for seq in range(2):
                first.send(item_to_message(first.mav, ITEMS[seq], 1, 1))
            # The vehicle's answers reach every client on its port: wait for the acceptance.
            accepted = wait_for(
                first,
                lambda m: m.get_type() == "MISSION_ACK" and m.type == mavlink.MAV_MISSION_ACCEPTED,
            )
            assert accepted is not None
        finally:
            other.close()
        assert vehicle.mission[1:] == ITEMS[1:2]
        assert vehicle.acks_sent.count(refusal) == (1 if quiet else 2)


def test_two_uploads_with_the_same_ids_interleaving_are_aborted_not_mixed():
    """Two senders the vehicle cannot tell apart (same ids, same address): the same item comes
    twice with different contents. Nothing of either is stored (this mock's addition where the
    autopilot answers an item out of sequence: ArduPilot; PX4 ignores one)."""
    other = [MissionItem(i, 0, 16, x=it.x + 999, y=it.y, z=50.0) for i, it in enumerate(ITEMS)]
    with vehicle_and_peer("ardupilot", request_timeout=30.0) as (vehicle, link):
        upload_raw(link, ITEMS[:2])
        link.send(link.mav.mission_count_encode(1, 1, 4, 0))
        assert wait_for(link, of("MISSION_REQUEST")) is not None
        link.send(item_to_message(link.mav, other[0], 1, 1))  # uploader B answers first
        assert wait_for(link, lambda m: m.get_type() == "MISSION_REQUEST" and m.seq == 1)
        link.send(item_to_message(link.mav, other[1], 1, 1))
        assert wait_for(link, lambda m: m.get_type() == "MISSION_REQUEST" and m.seq == 2)
        link.send(item_to_message(link.mav, ITEMS[1], 1, 1))  # uploader A's item 1
        ack = wait_for(link, of("MISSION_ACK"))
        assert ack is not None and ack.type == mavlink.MAV_MISSION_ERROR
        assert vehicle.missions.conflicts == 1
        assert any("interleaved" in t for t in vehicle.statustexts)
        assert vehicle.mission[1:] == ITEMS[1:2]


def test_mission_start_with_home_alone_is_denied():
    from gcs_planner.scenario.generate import random_scenario

    with vehicle_and_peer("ardupilot", scenario=random_scenario(5, 0)) as (vehicle, link):
        link.send(link.mav.command_long_encode(1, 1, mavlink.MAV_CMD_MISSION_START, 0, 0, 0, 0, 0,
                                               0, 0, 0))  # fmt: skip
        ack = wait_for(link, of("COMMAND_ACK"))
        assert ack is not None and ack.result == mavlink.MAV_RESULT_DENIED
        assert len(vehicle.mission) == 1


# Issue 26 -------------------------------------------------------------------------------------


def upload_result(link: Link, items: list[MissionItem]) -> int:
    """Upload by hand, answering every request, and return the MISSION_ACK's result."""
    link.send(link.mav.mission_count_encode(1, 1, len(items), 0))
    kinds = ("MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK")
    while True:
        msg = wait_for(link, lambda m: m.get_type() in kinds)
        assert msg is not None, "the vehicle fell silent mid-upload"
        if msg.get_type() == "MISSION_ACK":
            return int(msg.type)
        link.send(item_to_message(link.mav, items[msg.seq], 1, 1))


WP = MissionItem(0, 3, 16, x=305_000_000, y=1_235_000_000, z=100.0)
UNSUPPORTED_ON_PX4 = [
    # NAV_LOITER_TURNS: PX4 has no mission item for it (mavlink_mission.cpp).
    MissionItem(1, 3, 18, param1=2.0, param3=200.0, x=305_010_000, y=1_235_000_000, z=300.0),
    # A NAV_WAYPOINT in frame MISSION, and CONDITION_CHANGE_ALT: not in PX4's lists either.
    MissionItem(1, 2, 16, x=0, y=0, z=0.0),
    MissionItem(1, 2, 113, param1=1.0, z=300.0),
]


@pytest.mark.parametrize("odd", UNSUPPORTED_ON_PX4, ids=["loiter_turns", "wp_frame2", "cond_alt"])
def test_px4_refuses_the_whole_upload_holding_an_item_it_does_not_support(odd):
    """A real PX4 answers MAV_MISSION_UNSUPPORTED and keeps the mission it had; the mock
    accepted NAV_LOITER_TURNS and its flight skipped it."""
    items = [WP, odd.with_seq(1), WP.with_seq(2)]
    with vehicle_and_peer("px4", request_timeout=30.0) as (vehicle, link):
        upload_raw(link, ITEMS[:2])
        assert upload_result(link, items) == mavlink.MAV_MISSION_UNSUPPORTED
        assert vehicle.mission == ITEMS[:2]
        assert any(f"command {odd.command} not supported" in t for t in vehicle.statustexts)
        assert still_answers(link)


def test_ardupilot_takes_loiter_turns():
    items = [WP, UNSUPPORTED_ON_PX4[0], WP.with_seq(2)]
    with vehicle_and_peer("ardupilot", request_timeout=30.0) as (vehicle, link):
        assert upload_result(link, items) == mavlink.MAV_MISSION_ACCEPTED
        assert [it.command for it in vehicle.mission] == [16, 18, 16]


def flight_scenario():
    import numpy as np

    from gcs_planner.scenario.generate import DATASET1
    from gcs_planner.scenario.model import Kind, Origin, Scenario

    xyz = np.array([[i * 12_000.0, 0.0, 5000.0] for i in range(5)])
    return Scenario(
        ids=("A", "V1", "H1", "V2", "B"),
        xyz=xyz,
        kind=np.array([Kind.A, Kind.V, Kind.H, Kind.V, Kind.B], dtype=np.uint8),
        unreliable=np.zeros(5, bool),
        params=DATASET1,
        origin=Origin(30.5, 123.5, 0.0),
    )


def flight_items(flavour: str) -> list[MissionItem]:
    from gcs_planner.scenario.georef import LocalFrame

    sc = flight_scenario()
    frame = LocalFrame(sc.origin)
    points = [sc.xyz[0], *sc.xyz] if flavour == "ardupilot" else list(sc.xyz)
    out = []
    for k, p in enumerate(points):
        lat, lon, alt = frame.to_geodetic(*p)
        out.append(MissionItem(k, 0, 16, param2=1.0, x=round(lat * 1e7), y=round(lon * 1e7),
                               z=float(alt)))  # fmt: skip
    return out


AUTO = {"ardupilot": (1.0, 10.0, 0.0), "px4": (1.0, 4.0, 4.0)}  # DO_SET_MODE params 1-3


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_do_set_mode_to_the_mission_mode_flies_and_the_landed_state_follows(flavour):
    """MAV_CMD_DO_SET_MODE (custom mode enabled; ArduPlane AUTO 10, PX4 main AUTO 4 / sub
    MISSION 4) is how MAVSDK starts a mission: the mock answered UNSUPPORTED. EXTENDED_SYS_STATE
    says ON_GROUND before, IN_AIR during and ON_GROUND after the flight (it sent none)."""
    landed: list[int] = []
    with vehicle_and_peer(flavour, scenario=flight_scenario(), speedup=None) as (vehicle, link):
        upload_raw(link, flight_items(flavour))
        first = wait_for(link, of("EXTENDED_SYS_STATE"))
        assert first is not None
        landed.append(first.landed_state)
        link.send(link.mav.command_long_encode(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0,
                                               *AUTO[flavour], 0, 0, 0, 0))  # fmt: skip
        ack = wait_for(link, of("COMMAND_ACK"))
        assert ack is not None and ack.command == mavlink.MAV_CMD_DO_SET_MODE
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED

        def watch(m: Any) -> bool:
            if m.get_type() == "EXTENDED_SYS_STATE":
                if m.landed_state != landed[-1]:
                    landed.append(m.landed_state)
                return len(landed) >= 3
            return False

        assert wait_for(link, watch) is not None
        vehicle._fly_thread.join(PROOF_S)
    on_ground, in_air = mavlink.MAV_LANDED_STATE_ON_GROUND, mavlink.MAV_LANDED_STATE_IN_AIR
    assert landed == [on_ground, in_air, on_ground]
    assert vehicle.last_report is not None and vehicle.flight_errors == 0


@pytest.mark.parametrize(
    ("flavour", "params", "result"),
    [
        ("ardupilot", (1.0, 11.0, 0.0), mavlink.MAV_RESULT_FAILED),  # RTL: not modelled
        ("ardupilot", (0.0, 10.0, 0.0), mavlink.MAV_RESULT_DENIED),  # no custom-mode flag
        ("ardupilot", (math.nan, 10.0, 0.0), mavlink.MAV_RESULT_DENIED),
        ("px4", (1.0, 4.0, 3.0), mavlink.MAV_RESULT_TEMPORARILY_REJECTED),  # AUTO/LOITER
        ("px4", (math.nan, 4.0, 4.0), mavlink.MAV_RESULT_TEMPORARILY_REJECTED),
    ],
)
def test_do_set_mode_to_another_mode_is_refused_and_nothing_flies(flavour, params, result):
    with vehicle_and_peer(flavour, scenario=flight_scenario(), speedup=None) as (vehicle, link):
        upload_raw(link, flight_items(flavour))
        link.send(link.mav.command_long_encode(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, *params,
                                               0, 0, 0, 0))  # fmt: skip
        ack = wait_for(link, of("COMMAND_ACK"))
        assert ack is not None and ack.result == result
        assert still_answers(link)
    assert vehicle.last_report is None and not vehicle.flying


def test_do_set_mode_auto_with_nothing_to_fly_is_denied():
    with vehicle_and_peer("px4", scenario=flight_scenario()) as (vehicle, link):
        link.send(link.mav.command_long_encode(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, *AUTO["px4"],
                                               0, 0, 0, 0))  # fmt: skip
        ack = wait_for(link, of("COMMAND_ACK"))
        assert ack is not None and ack.result == mavlink.MAV_RESULT_DENIED
