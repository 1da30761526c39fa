"""A real third-party ground station watches a flight: MAVSDK (native binding) connected to the
mock vehicle over loopback UDP sees it armed, the position move, the items reached and a
STATUSTEXT for each correction."""

from __future__ import annotations

import threading

import numpy as np
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from mavsdk import ComponentType, Configuration, Mavsdk
from mavsdk.plugins.mission_raw import MissionItem as RawItem
from mavsdk.plugins.mission_raw import MissionRaw
from mavsdk.plugins.telemetry import Telemetry

from gcs_planner.mission.items import MissionItem
from gcs_planner.scenario.generate import DATASET1
from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.scenario.model import Kind, Origin, Scenario

ORIGIN = Origin(30.5, 123.5, 0.0)
WAIT_S = 60.0  # generous: a busy machine; every wait ends on the event it waits for


def scenario() -> Scenario:
    xyz = np.array([[i * 12_000.0, 0.0, 5000.0] for i in range(5)])
    return Scenario(
        ids=("A", "V1", "H1", "V2", "B"),
        xyz=xyz,
        kind=np.array([Kind.A, Kind.V, Kind.H, Kind.V, Kind.B], dtype=np.uint8),
        unreliable=np.zeros(5, bool),
        params=DATASET1,
        origin=ORIGIN,
    )


def raw_items(sc: Scenario) -> list[RawItem]:
    """Home, then a waypoint on each point with a 1 m acceptance radius (ArduPlane param2)."""
    frame = LocalFrame(ORIGIN)
    items: list[MissionItem] = []
    for k, p in enumerate([sc.xyz[0], *sc.xyz]):
        lat, lon, alt = frame.to_geodetic(*p)
        items.append(
            MissionItem(k, 0, 16, param2=0.0 if k == 0 else 1.0, x=round(lat * 1e7),
                        y=round(lon * 1e7), z=float(alt))
        )  # fmt: skip
    return [
        RawItem(it.seq, it.frame, it.command, int(it.seq == 0), 1, it.param1, it.param2,
                it.param3, it.param4, it.x, it.y, it.z, 0)
        for it in items
    ]  # fmt: skip


def test_mavsdk_watches_the_mock_vehicle_fly():
    sc = scenario()
    port = free_udp_port()
    gcs = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    positions: list[tuple[float, float]] = []
    texts: list[str] = []
    progress: list[int] = []
    armed: list[bool] = []
    done = threading.Event()
    lock = threading.Lock()

    def on_position(pos, *_):
        with lock:
            positions.append((pos.latitude_deg, pos.longitude_deg))

    def on_text(st, *_):
        with lock:
            texts.append(st.text)
            if sum("fix" in t for t in texts) >= 3:
                done.set()

    def on_progress(p, *_):
        with lock:
            progress.append(p.current)

    def on_armed(a, *_):
        with lock:
            armed.append(bool(a))

    try:
        assert int(gcs.add_any_connection(f"udpin://127.0.0.1:{port}")) == 0
        with MockVehicle(f"udpout:127.0.0.1:{port}", flavour="ardupilot", scenario=sc) as vehicle:
            system = gcs.first_autopilot(timeout_s=WAIT_S)
            assert system is not None
            mission = MissionRaw(system)  # subscribed before the upload: MAVSDK tracks it
            mission.subscribe_mission_progress(on_progress)
            mission.upload_mission(raw_items(sc))
            telemetry = Telemetry(system)
            telemetry.subscribe_position(on_position)
            telemetry.subscribe_status_text(on_text)
            telemetry.subscribe_armed(on_armed)
            report = vehicle.fly(seed=0, time_scale=None, position_messages=200)
            assert done.wait(WAIT_S)
    finally:
        gcs.destroy()
    assert report.arrived
    with lock:
        lons = [p[1] for p in positions]
        assert len(positions) >= 10
        assert max(lons) - min(lons) > 0.3  # ~48 km at 30.5 N: the position moved
        assert [t for t in texts if "fix" in t and "made" in t] and len(texts) >= 3
        assert any(armed)
        # The items were reached in order up to B (seq 5; home is 0).
        assert progress == sorted(progress) and max(progress) >= 5
