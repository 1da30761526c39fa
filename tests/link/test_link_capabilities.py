"""AUTOPILOT_VERSION, which the automatic choice of MAVFTP needs: asked once a session, at
connect, and answered while the command does what it does first; a vehicle that never answers
costs what is left of one timeout from connect, not three full waits from when the transfer
asked (4.5 s a transfer before).

No test asserts wall-clock time: what is counted is what the vehicle was asked."""

from __future__ import annotations

import time

from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.mission.items import MissionItem

ASKS = (mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES)
ITEMS = [MissionItem(i, 0, 16, x=305_000_000 + i, y=1_235_000_000, z=100.0) for i in range(6)]


def _asks(vehicle: MockVehicle) -> int:
    return sum(1 for command, _ in vehicle.commands if command in ASKS)


def test_the_capabilities_are_asked_at_connect_and_kept_from_any_reader():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}") as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, timeout=0.5)
            client.connect(timeout=10.0)
            # A parameter read reads the link itself: the answer that comes meanwhile is kept.
            client.check_loiter_parameter()
            deadline = time.monotonic() + 10.0
            while client.capabilities is None and time.monotonic() < deadline:
                client.check_loiter_parameter()
            assert client.capabilities is not None and _asks(vehicle) == 2
            report = client.upload_verified(ITEMS)
            assert report.transfer == "ftp" and _asks(vehicle) == 2  # not asked again
        finally:
            link.close()


def test_a_silent_vehicle_is_asked_within_one_timeout_and_goes_by_the_mission_protocol():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}") as vehicle:
        vehicle._autopilot_version = lambda: None  # type: ignore[method-assign]
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, timeout=0.5)
            client.connect(timeout=10.0)
            report = client.upload_verified(ITEMS)
            assert report.transfer == "mission" and client.capabilities == 0
            # MAV_CMD_REQUEST_MESSAGE and the older command, each a third of the timeout apart
            assert 2 <= (asked := _asks(vehicle)) <= 6
            client.download()
            assert _asks(vehicle) == asked  # once a session
        finally:
            link.close()


def test_no_vehicle_the_transfer_choice_does_not_need_is_asked():
    port = free_udp_port()
    for flavour, transfer in (("px4", "auto"), ("ardupilot", "mission")):
        with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour) as vehicle:
            link = open_link(f"udpout:127.0.0.1:{port}")
            try:
                client = MissionClient(link, transfer=transfer)
                client.connect(timeout=10.0)
                assert client.upload_verified(ITEMS).transfer == "mission"
            finally:
                link.close()
            assert _asks(vehicle) == 0
