"""Real third-party peers: MAVSDK (native v4 binding) as the ground station against the mock
vehicle, and MAVSDK's MissionRawServer as the vehicle for the project's client."""

from __future__ import annotations

import threading

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from mavsdk import ComponentType, Configuration, Mavsdk
from mavsdk.plugins.mission_raw import MissionItem as RawItem
from mavsdk.plugins.mission_raw import MissionRaw
from mavsdk.plugins.mission_raw_server import MissionRawServer

from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import mission_differences
from gcs_planner.mission.builder import Mission
from gcs_planner.mission.items import MissionItem
from gcs_planner.mission.qgc_plan import read_plan, write_plan
from gcs_planner.scenario.model import Origin

_FIELDS = ("seq", "frame", "command", "autocontinue", "param1", "param2", "param3", "param4")


def project_items(firmware: str) -> list[MissionItem]:
    items: list[MissionItem] = []
    if firmware == "ardupilot":
        items.append(MissionItem(0, 0, 16, x=305_000_000, y=1_235_000_000, z=5000.0, note="home"))
    items.append(MissionItem(len(items), 2, 178, param1=0.0, param2=25.0, param3=-1.0))
    for i in range(12):
        items.append(
            MissionItem(len(items), 0, 16, param2=50.0, x=305_000_000 + 4321 * i,
                        y=1_235_000_000 + 2345 * i, z=5000.0 + 3.5 * i)
        )  # fmt: skip
    items.append(MissionItem(len(items), 0, 17, param3=-200.0, x=items[-1].x, y=items[-1].y,
                             z=items[-1].z))  # fmt: skip
    return items


def to_raw(items: list[MissionItem]) -> list[RawItem]:
    return [
        RawItem(it.seq, it.frame, it.command, int(it.seq == 0), it.autocontinue, it.param1,
                it.param2, it.param3, it.param4, it.x, it.y, it.z, it.mission_type)
        for it in items
    ]  # fmt: skip


def from_raw(raw) -> list[MissionItem]:
    return [
        MissionItem(r.seq, r.frame, r.command, r.current, r.autocontinue, r.param1, r.param2,
                    r.param3, r.param4, r.x, r.y, r.z, r.mission_type)
        for r in raw
    ]  # fmt: skip


def mavsdk_instance(kind: ComponentType) -> Mavsdk:
    return Mavsdk(Configuration.create_with_component_type(kind))


def test_mavsdk_imports_the_projects_plan_uploads_to_mock_vehicle_and_downloads_it_identical(
    tmp_path,
):
    items = project_items("px4")
    mission = Mission(
        items=tuple(items),
        firmware="px4",
        home=(30.5, 123.5, 5000.0),
        cruise_speed=25.0,
        turn_radius=200.0,
        loiter_param=("NAV_LOITER_RAD", 200.0),
        acceptance_radius=50.0,
        origin=Origin(30.5, 123.5, 0.0),
        origin_is_default=False,
    )
    path = write_plan(mission, tmp_path / "route.plan")
    port = free_udp_port()
    gcs = mavsdk_instance(ComponentType.GROUND_STATION)
    try:
        assert int(gcs.add_any_connection(f"udpin://127.0.0.1:{port}")) == 0
        with MockVehicle(f"udpout:127.0.0.1:{port}", flavour="px4") as vehicle:
            system = gcs.first_autopilot(timeout_s=10.0)
            assert system is not None
            raw = MissionRaw(system)
            imported = raw.import_qgroundcontrol_mission(str(path)).mission_items
            assert len(imported) == len(items)
            raw.upload_mission(imported)
            stored = vehicle.mission
            back = from_raw(raw.download_mission())
    finally:
        gcs.destroy()
    ours = list(read_plan(path).items)
    assert not mission_differences(ours, stored)
    assert not mission_differences(from_raw(imported), back)
    assert not mission_differences(ours, back)


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_mavsdk_mission_raw_against_mock_vehicle_both_flavours(flavour):
    items = project_items(flavour)
    port = free_udp_port()
    gcs = mavsdk_instance(ComponentType.GROUND_STATION)
    try:
        assert int(gcs.add_any_connection(f"udpin://127.0.0.1:{port}")) == 0
        with MockVehicle(f"udpout:127.0.0.1:{port}", flavour=flavour) as vehicle:
            system = gcs.first_autopilot(timeout_s=10.0)
            assert system is not None
            raw = MissionRaw(system)
            raw.upload_mission(to_raw(items))
            stored = vehicle.mission
            back = from_raw(raw.download_mission())
    finally:
        gcs.destroy()
    home = flavour == "ardupilot"
    assert not mission_differences(items, stored, skip_home=home)
    assert not mission_differences(items, back, skip_home=home)
    # What MAVSDK reads back is what the vehicle holds, home included.
    assert not mission_differences(stored, back)


def test_project_client_uploads_to_mavsdk_mission_raw_server_and_reads_back():
    items = project_items("px4")
    port = free_udp_port()
    autopilot = mavsdk_instance(ComponentType.AUTOPILOT)
    received = []
    arrived = threading.Event()

    def on_mission(result, plan, _user_data=None):
        received.append((result, plan))
        arrived.set()

    try:
        assert int(autopilot.add_any_connection(f"udpin://127.0.0.1:{port}")) == 0
        server = MissionRawServer(autopilot.server_component())
        server.subscribe_incoming_mission(on_mission)
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link)
            vehicle = client.connect(timeout=10.0)
            assert vehicle.component == 1
            report = client.upload_verified(items)
            assert report.items == len(items)
            assert arrived.wait(5.0)
            again = client.download()
        finally:
            link.close()
    finally:
        autopilot.destroy()
    server_items = from_raw(received[-1][1].mission_items)
    assert not mission_differences(items, server_items)
    assert not mission_differences(items, again)


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_mavsdk_start_mission_flies_the_mock(flavour):
    """Issue 26: MAVSDK's ``start_mission()`` sets the mission mode with MAV_CMD_DO_SET_MODE
    (ArduPlane AUTO; PX4 AUTO/MISSION), which the mock answered UNSUPPORTED (MAVSDK raised)."""
    from support.flights import line_scenario, waypoint_items

    sc = line_scenario()
    port = free_udp_port()
    gcs = mavsdk_instance(ComponentType.GROUND_STATION)
    try:
        assert int(gcs.add_any_connection(f"udpin://127.0.0.1:{port}")) == 0
        with MockVehicle(
            f"udpout:127.0.0.1:{port}", flavour=flavour, scenario=sc, speedup=20_000.0
        ) as vehicle:
            system = gcs.first_autopilot(timeout_s=30.0)
            assert system is not None
            raw = MissionRaw(system)
            raw.upload_mission(to_raw(waypoint_items(sc, flavour)))
            raw.start_mission()  # raises on a refusal
            assert vehicle._fly_thread is not None
            vehicle._fly_thread.join(60.0)
            assert not vehicle._fly_thread.is_alive()
    finally:
        gcs.destroy()
    # What MAVSDK sent: DO_SET_MODE (176), accepted.
    assert (176, 0) in vehicle.commands
    assert vehicle.last_report is not None and vehicle.flight_errors == 0
