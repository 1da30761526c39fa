"""dronekit2 (the maintained fork of DroneKit-Python) uploads and downloads missions with the mock
vehicle of both flavours over UDP on 127.0.0.1, as it would with ArduPilot or PX4."""

from __future__ import annotations

import time

import dronekit
import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from pymavlink import mavutil

from gcs_planner.mission.items import MissionItem

WAYPOINTS = [(30.5 + 0.001 * i, 123.5 + 0.002 * i, 100.0 + i) for i in range(5)]


def _wait_until_idle(vehicle: MockVehicle) -> None:
    """dronekit sends no MISSION_ACK after a download and does not count again when refused.
    PX4 keeps sending its list until that ACK or its 5 s operation timeout, and meanwhile
    refuses a clear and an upload ("IGN CLEAR CMD: Busy", "IGN MISSION_COUNT: Busy";
    mavlink_mission.cpp), so with PX4 a dronekit script must wait that out; ArduPilot keeps no
    download state."""
    deadline = time.monotonic() + 30.0
    while vehicle.missions.download is not None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert vehicle.missions.download is None


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_dronekit_uploads_and_downloads_a_mission(flavour):
    port = free_udp_port()
    with MockVehicle(f"udpout:127.0.0.1:{port}", flavour=flavour) as vehicle:
        if flavour == "px4":
            # dronekit asks an empty mission for its item 0 (home, on ArduPilot) and waits for
            # it forever, so a PX4 vehicle is given a mission of two items to start with.
            vehicle.missions.commit([MissionItem(i, 0, 16, x=305_000_000, y=1_235_000_000,
                                                 z=50.0) for i in range(2)])  # fmt: skip
        drone = dronekit.connect(f"udpin:127.0.0.1:{port}", wait_ready=False, heartbeat_timeout=60)
        try:
            cmds = drone.commands
            cmds.download()
            cmds.wait_ready(timeout=60)
            # dronekit keeps item 0 as home, the ArduPilot way: ArduPilot gave it its home.
            assert drone._wploader.count() == (1 if flavour == "ardupilot" else 2)
            _wait_until_idle(vehicle)
            cmds.clear()
            for lat, lon, alt in WAYPOINTS:
                cmds.add(
                    dronekit.Command(
                        0, 0, 0, mavutil.mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                        mavutil.mavlink.MAV_CMD_NAV_WAYPOINT, 0, 0, 0, 0, 0, 0, lat, lon, alt,
                    )
                )  # fmt: skip
            cmds.upload(timeout=60)
            sent = [drone._wploader.wp(i) for i in range(drone._wploader.count())]
            held = vehicle.mission
            assert len(held) == len(sent)
            first = 1 if flavour == "ardupilot" else 0  # ArduPilot keeps its own home
            for want, got in zip(sent[first:], held[first:]):
                assert abs(got.x - round(want.x * 1e7)) <= 10 and abs(got.z - want.z) < 1e-3
            cmds.download()
            cmds.wait_ready(timeout=60)
            back = [drone._wploader.wp(i) for i in range(drone._wploader.count())]
            assert len(back) == len(sent)
            # MISSION_ITEM carries degrees as float32: about 2e-6 degrees at 30 N.
            for want, got in zip(sent[first:], back[first:]):
                assert abs(got.x - want.x) < 1e-5 and abs(got.y - want.y) < 1e-5
        finally:
            drone.close()
