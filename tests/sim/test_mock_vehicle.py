"""The vehicle side on its own, driven by a raw pymavlink peer: sequence, timeouts, no final
acknowledgement, parameters, duplicates; and the seeded fault injector."""

from __future__ import annotations

import time

import pytest
from gcs_planner.sim.faults import FaultInjector, FaultRates
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from hypothesis import given, settings
from hypothesis import strategies as st

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.mission.items import MissionItem

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

ITEMS = [MissionItem(i, 0, 16, x=305_000_000 + i, y=1_235_000_000, z=100.0) for i in range(4)]


def _collect(link, types, seconds):
    out = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        msg = link.recv(0.05)
        if msg is not None and msg.get_type() in types:
            out.append(msg)
    return out


def _raw_peer(port):
    link = open_link(f"udpout:127.0.0.1:{port}")
    link.send(link.mav.heartbeat_encode(6, 8, 0, 0, 4))
    return link


def test_heartbeat_and_mission_current_as_a_fixed_wing():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", heartbeat_period=0.2):
        link = _raw_peer(port)
        try:
            msgs = _collect(link, {"HEARTBEAT", "MISSION_CURRENT"}, 1.3)
        finally:
            link.close()
    beats = [m for m in msgs if m.get_type() == "HEARTBEAT"]
    assert len(beats) >= 3
    assert all(m.type == mavlink.MAV_TYPE_FIXED_WING for m in beats)
    assert all(m.autopilot == mavlink.MAV_AUTOPILOT_PX4 for m in beats)
    assert all(m.get_srcComponent() == 1 for m in beats)
    assert any(m.get_type() == "MISSION_CURRENT" for m in msgs)


def _quiet(flavour):
    return autopilot_for(flavour).protocol.refuses_quietly


_REQUESTS = {"MISSION_REQUEST", "MISSION_REQUEST_INT"}


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_wrong_sequence_is_refused_and_the_item_asked_again(flavour):
    """ArduPilot answers an item out of sequence MAV_MISSION_INVALID_SEQUENCE
    (MissionItemProtocol::handle_mission_item); PX4 ignores it ("Item sequence not expected,
    ignore item"). Both ask for the item they wait for again."""
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour, request_timeout=0.2) as vehicle:
        link = _raw_peer(port)
        try:
            link.send(link.mav.mission_count_encode(1, 1, 3, 0))
            _collect(link, _REQUESTS, 0.1)
            wrong = ITEMS[2]
            link.send(
                link.mav.mission_item_int_encode(
                    1, 1, 2, wrong.frame, wrong.command, 0, 1, 0, 0, 0, 0, wrong.x, wrong.y, 100.0
                )
            )
            msgs = _collect(link, {"MISSION_ACK", *_REQUESTS}, 0.6)
        finally:
            link.close()
    acks = [m.type for m in msgs if m.get_type() == "MISSION_ACK"]
    assert acks == ([] if _quiet(flavour) else [mavlink.MAV_MISSION_INVALID_SEQUENCE])
    assert [m.seq for m in msgs if m.get_type() in _REQUESTS][-1] == 0
    assert vehicle.mission[1:] == []


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_silent_uploader_is_re_requested_then_cancelled(flavour):
    """ArduPilot ends a silent upload with MISSION_ACK OPERATION_CANCELLED
    (MissionItemProtocol::update); PX4 with the status text "Operation timeout" only
    (MavlinkMissionManager::send)."""
    port = free_udp_port()
    with MockVehicle(
        f"udpin:127.0.0.1:{port}", flavour=flavour, request_timeout=0.1, upload_timeout=0.6
    ) as vehicle:
        link = _raw_peer(port)
        try:
            link.send(link.mav.mission_count_encode(1, 1, 3, 0))
            msgs = _collect(link, {"MISSION_ACK", *_REQUESTS}, 1.2)
        finally:
            link.close()
        assert vehicle.missions.upload is None
    requests = [m for m in msgs if m.get_type() in _REQUESTS]
    assert len(requests) >= 3 and all(m.seq == 0 for m in requests)
    acks = [m.type for m in msgs if m.get_type() == "MISSION_ACK"]
    if _quiet(flavour):
        assert acks == [] and "Operation timeout" in vehicle.statustexts
    else:
        assert acks == [mavlink.MAV_MISSION_OPERATION_CANCELLED]
    assert vehicle.mission[1:] == []


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_download_needs_no_final_ack_and_busy_vehicle_refuses(flavour):
    """A download whose final MISSION_ACK never comes: ArduPilot keeps no download state and
    takes the next upload at once; PX4 is still sending its list and answers the count
    MAV_MISSION_ERROR, which the client ends with a cancel and counts again. While receiving,
    ArduPilot denies a download; PX4 ignores it with a status text."""
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour) as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link)
            client.connect(5.0)
            client.upload(ITEMS)
            # A download that never sends its final MISSION_ACK...
            link.send(link.mav.mission_request_list_encode(1, 1, 0))
            assert _collect(link, {"MISSION_COUNT"}, 0.3)[0].count == 4
            link.send(link.mav.mission_request_int_encode(1, 1, 0, 0))
            assert _collect(link, {"MISSION_ITEM_INT"}, 0.3)[0].seq == 0
            # ...and the next upload is taken.
            new = ITEMS[:2]
            client.upload(new)
            assert vehicle.mission[1:] == new[1:]
            busy_errors = vehicle.acks_sent.count(mavlink.MAV_MISSION_ERROR)
            assert busy_errors == (1 if _quiet(flavour) else 0)
            link.send(link.mav.mission_count_encode(1, 1, 3, 0))
            link.send(link.mav.mission_request_list_encode(1, 1, 0))
            acks = _collect(link, {"MISSION_ACK"}, 0.3)
        finally:
            link.close()
    if _quiet(flavour):
        assert "Mission download request ignored, already active" in vehicle.statustexts
    else:
        assert mavlink.MAV_MISSION_DENIED in [m.type for m in acks]


def test_parameters_read_list_and_set():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="ardupilot") as vehicle:
        link = _raw_peer(port)
        try:
            link.send(link.mav.param_request_list_encode(1, 1))
            names = {m.param_id for m in _collect(link, {"PARAM_VALUE"}, 0.4)}
            assert "WP_LOITER_RAD" in names
            link.send(link.mav.param_set_encode(1, 1, b"WP_LOITER_RAD", 187.6, 4))
            values = _collect(link, {"PARAM_VALUE"}, 0.3)
            assert values[0].param_value == 188.0  # an INT16 parameter rounds
            link.send(link.mav.param_request_read_encode(1, 1, b"", 0))
            assert _collect(link, {"PARAM_VALUE"}, 0.3)[0].param_index == 0
        finally:
            link.close()
    assert vehicle.parameters["WP_LOITER_RAD"] == 188.0


def test_exact_link_duplicates_are_dropped():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        link = _raw_peer(port)
        try:
            buf = link.mav.mission_clear_all_encode(1, 1, 0).pack(link.mav)
            link.write_raw(buf)
            link.write_raw(buf)  # same bytes, same MAVLink sequence number
            acks = _collect(link, {"MISSION_ACK"}, 0.4)
        finally:
            link.close()
    assert len(acks) == 1
    assert vehicle.acks_sent.count(mavlink.MAV_MISSION_ACCEPTED) == 1


@settings(max_examples=40, deadline=None)
@given(
    st.integers(0, 2**31),
    st.floats(0, 1),
    st.floats(0, 1),
    st.floats(0, 1),
    st.floats(0, 1),
)
def test_fault_injector_conserves_frames_and_is_seeded(seed, drop, dup, delay, reorder):
    rates = FaultRates(drop, dup, delay, reorder, delay_s=0.01)

    def run():
        inj = FaultInjector(rates, seed)
        out = []
        for i in range(200):
            out += inj.push(i, i * 0.001)
        out += inj.due(10.0)
        return inj, out

    inj, out = run()
    assert run()[1] == out  # same seed, same traffic: same faults
    c = inj.counts
    assert inj.pending() == 0
    # Every frame comes out as many times as it was copied, minus drops; nothing is invented.
    assert len(out) == 200 - c.dropped + c.duplicated
    assert set(out) <= set(range(200))
    assert all(out.count(i) <= 2 for i in set(out))
    if drop == 0 and dup == 0:
        assert sorted(out) == list(range(200))
    if not rates.any:
        assert out == list(range(200))


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_final_item_resent_after_a_lost_ack_is_acknowledged_again(flavour):
    """PX4 acknowledges its partner's last item again (its ACK was lost; handle_mission_item_both
    while idle) and answers any other item MAV_MISSION_ERROR ("No transfer"); ArduPilot, no
    longer receiving, answers every item MAV_MISSION_ERROR (GCS_MAVLINK::handle_mission_item)."""
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour, request_timeout=0.5) as vehicle:
        link = _raw_peer(port)
        try:
            link.send(link.mav.mission_count_encode(1, 1, 2, 0))

            def item(seq):
                it = ITEMS[seq]
                return link.mav.mission_item_int_encode(
                    1, 1, seq, it.frame, it.command, 0, 1, 0, 0, 0, 0, it.x, it.y, 100.0
                )

            _collect(link, _REQUESTS, 0.1)
            link.send(item(0))
            _collect(link, _REQUESTS, 0.1)
            link.send(item(1))
            first = _collect(link, {"MISSION_ACK"}, 0.3)
            link.send(item(1))  # as if that acknowledgement had been lost
            again = _collect(link, {"MISSION_ACK"}, 0.3)
            link.send(item(0))  # an older item is not the end of the transfer
            stale = _collect(link, {"MISSION_ACK"}, 0.3)
        finally:
            link.close()
    assert [m.type for m in first] == [mavlink.MAV_MISSION_ACCEPTED]
    final_again = autopilot_for(flavour).protocol.final_item_again
    assert [m.type for m in again] == [final_again]
    assert [m.type for m in stale] == [mavlink.MAV_MISSION_ERROR]
    assert len(vehicle.mission) == 2


def test_consecutive_download_processes_are_each_answered_first_time(tmp_path):
    """Issue 26: every `gcs-planner download` starts its MAVLink sequence at 0, so its frames
    are byte-identical to its predecessor's; the vehicle dropped them as duplicates (no time
    limit, no address), and a download got its answer only after resending. With no resends
    allowed (--retries 0; generous waits) each of three processes must be answered."""
    import subprocess
    import sys

    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        client = MissionClient(open_link(f"udpout:127.0.0.1:{port}"))
        try:
            client.connect(timeout=30.0)
            client.upload(ITEMS)
        finally:
            client.link.close()
        for k in range(3):
            out = tmp_path / f"back{k}.json"
            run = subprocess.run(
                [sys.executable, "-m", "gcs_planner", "download", "--connect",
                 f"udpout:127.0.0.1:{port}", "--retries", "0", "--timeout", "10", "--wait", "30",
                 "--quiet", "--out", str(out)],
                capture_output=True, text=True, timeout=120,
            )  # fmt: skip
            assert run.returncode == 0, run.stderr
            assert out.exists()
    assert vehicle.duplicates_dropped == 0


def test_a_one_shot_request_from_each_new_client_is_answered():
    """A PARAM_REQUEST_READ sent once by a fresh client (a script, a one-shot tool) is the
    same bytes as the last one's: it went unanswered."""
    port = free_udp_port()
    answered = 0
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="ardupilot"):
        for _ in range(4):
            link = open_link(f"udpout:127.0.0.1:{port}")
            try:
                link.send(link.mav.param_request_read_encode(1, 1, b"", 0))
                deadline = time.monotonic() + 10.0
                while time.monotonic() < deadline:
                    msg = link.recv(0.1)
                    if msg is not None and msg.get_type() == "PARAM_VALUE":
                        answered += 1
                        break
            finally:
                link.close()
    assert answered == 4


def test_a_copy_after_the_window_is_a_new_message():
    """The same bytes from the same address later than DUPLICATE_WINDOW_S are handled again
    (a radio's copy comes within milliseconds; this is a resend)."""
    from gcs_planner.sim.vehicle import DUPLICATE_WINDOW_S

    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        link = _raw_peer(port)
        try:
            buf = link.mav.mission_clear_all_encode(1, 1, 0).pack(link.mav)
            for copies in (1, 2):
                link.write_raw(buf)
                deadline = time.monotonic() + 10.0
                while vehicle.acks_sent.count(mavlink.MAV_MISSION_ACCEPTED) < copies:
                    assert time.monotonic() < deadline, f"copy {copies} was not handled"
                    time.sleep(0.05)
                # Handled, so stamped: the next copy comes well after the window.
                time.sleep(DUPLICATE_WINDOW_S + 1.0)
        finally:
            link.close()
    assert vehicle.duplicates_dropped == 0


def test_the_same_bytes_from_another_address_within_the_window_are_handled():
    """Two ground stations (two UDP ports) whose frames are byte-identical (same ids, same
    MAVLink sequence) within DUPLICATE_WINDOW_S: both are answered; only a copy from the same
    address is a link-level duplicate."""
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        first, second = _raw_peer(port), _raw_peer(port)
        try:
            bufs = [p.mav.mission_clear_all_encode(1, 1, 0).pack(p.mav) for p in (first, second)]
            assert bufs[0] == bufs[1]
            first.write_raw(bufs[0])
            second.write_raw(bufs[1])
            acks = [_collect(p, {"MISSION_ACK"}, 0.4) for p in (first, second)]
        finally:
            first.close()
            second.close()
    # The mock answers every peer it has heard: each hears both answers.
    assert all(a and all(m.type == mavlink.MAV_MISSION_ACCEPTED for m in a) for a in acks)
    assert vehicle.acks_sent.count(mavlink.MAV_MISSION_ACCEPTED) == 2
    assert vehicle.duplicates_dropped == 0
