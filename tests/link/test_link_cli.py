"""The commands as a user runs them from two terminals: `gcs-planner mock-vehicle` in one
process, `gcs-planner upload` / `download` in another, over UDP on 127.0.0.1."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from support.paths import DATA

from gcs_planner.cli import main
from gcs_planner.link.connection import open_link
from gcs_planner.mission.builder import Mission
from gcs_planner.mission.qgc_plan import read_plan, write_plan
from gcs_planner.scenario.model import Origin

WORKBOOK = DATA / "dataset1.xlsx"
FLAGS = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
         "--delta", "0.001"]  # fmt: skip


def _plan_file(tmp_path: Path, firmware: str) -> Path:
    from gcs_planner.mission.items import MissionItem

    items = []
    if firmware == "ardupilot":
        items.append(MissionItem(0, 0, 16, x=305_000_000, y=1_235_000_000, z=5000.0))
    for i in range(30):
        items.append(MissionItem(len(items), 0, 16, param2=50.0, x=305_000_000 + 999 * i,
                                 y=1_235_000_000 + 555 * i, z=5000.0 + i))  # fmt: skip
    mission = Mission(
        items=tuple(items),
        firmware=firmware,
        home=(30.5, 123.5, 5000.0),
        cruise_speed=25.0,
        turn_radius=200.0,
        loiter_param=None,
        acceptance_radius=50.0,
        origin=Origin(30.5, 123.5, 0.0),
        origin_is_default=False,
    )
    return write_plan(mission, tmp_path / "mission.plan")


def _stop(proc: subprocess.Popen, sig: int) -> str:
    """Signal the mock-vehicle process and return its stderr; fail if it does not stop."""
    proc.send_signal(sig)
    try:
        return proc.communicate(timeout=30)[1]
    except subprocess.TimeoutExpired:
        proc.kill()
        err = proc.communicate()[1]
        pytest.fail(f"mock-vehicle did not stop on signal {sig} within 30 s; stderr: {err}")


def test_upload_and_download_against_mock_vehicle_process(tmp_path, capsys):
    port = free_udp_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "gcs_planner", "mock-vehicle", "--connect",
         f"udpin:127.0.0.1:{port}", "--scenario", str(WORKBOOK), *FLAGS, "--flavour", "px4"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )  # fmt: skip
    try:
        plan = _plan_file(tmp_path, "px4")
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet"]
        code = main(["upload", str(plan), *conn, "--loiter-radius", "200"])
        out = capsys.readouterr().out
        assert code == 0, out
        assert "verified 30 items" in out
        dest = tmp_path / "back.json"
        assert main(["download", *conn, "--out", str(dest)]) == 0
        back = json.loads(dest.read_text())
        want = read_plan(plan).items
        assert [(r["x"], r["y"], r["command"]) for r in back["items"]] == [
            (it.x, it.y, it.command) for it in want
        ]
        # A PX4 mission is not written as .waypoints (readers disagree on its row 0).
        wp = tmp_path / "back.waypoints"
        assert main(["download", *conn, "--out", str(wp)]) == 2
        assert not wp.exists() and "use --out FILE.json" in capsys.readouterr().err
    finally:
        err = _stop(proc, signal.SIGINT)
    assert proc.returncode == 0
    assert "holds 30 items" in err


def test_mock_vehicle_process_stops_on_sigterm():
    port = free_udp_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "gcs_planner", "mock-vehicle", "--connect",
         f"udpin:127.0.0.1:{port}", "--scenario", "missions/example/scenario.toml"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )  # fmt: skip
    link = open_link(f"udpout:127.0.0.1:{port}")
    try:
        # Running: it answers with heartbeats once it hears from us.
        deadline = time.monotonic() + 20
        beat = None
        while beat is None and time.monotonic() < deadline:
            link.send(link.mav.heartbeat_encode(6, 8, 0, 0, 4))
            beat = link.recv(0.5)
        assert beat is not None
    finally:
        link.close()
        err = _stop(proc, signal.SIGTERM)
    assert proc.returncode == 0
    assert "mock vehicle stopped" in err


def test_upload_refuses_a_mission_for_the_other_firmware(tmp_path, capsys):
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        plan = _plan_file(tmp_path, "ardupilot")
        code = main(["upload", str(plan), "--connect", f"udpout:127.0.0.1:{port}", "--quiet"])
        assert code == 4
        assert "export it again with --autopilot px4" in capsys.readouterr().err
        assert vehicle.mission == []


@pytest.mark.parametrize("command", [["upload", "m.plan"], ["download", "--out", "m.json"]])
def test_upload_and_download_name_the_autopilot_with_autopilot(command, capsys):
    """--autopilot names the vehicle's autopilot; --firmware, its old name, still works and
    says it is deprecated."""
    from gcs_planner.cli import build_parser

    link = ["--connect", "udpout:127.0.0.1:14550"]
    new = build_parser([command[0]]).parse_args([*command, *link, "--autopilot", "px4"])
    assert new.autopilot == "px4" and "deprecated" not in capsys.readouterr().err
    old = build_parser([command[0]]).parse_args([*command, *link, "--firmware", "px4"])
    assert old.autopilot == "px4" and "--firmware is deprecated" in capsys.readouterr().err
    unset = build_parser([command[0]]).parse_args([*command, *link])
    assert unset.autopilot is None  # from the vehicle's heartbeat


def test_upload_without_vehicle_and_bad_files_exit_cleanly(tmp_path, capsys):
    port = free_udp_port()
    plan = _plan_file(tmp_path, "px4")
    args = ["--connect", f"udpout:127.0.0.1:{port}", "--wait", "0.5", "--quiet"]
    assert main(["upload", str(plan), *args]) == 4
    assert "no vehicle heartbeat" in capsys.readouterr().err
    bad = tmp_path / "x.kml"
    bad.write_text("nothing")
    assert main(["upload", str(bad), *args]) == 2
    assert "unknown mission file type" in capsys.readouterr().err
    assert main(["download", *args, "--out", str(tmp_path / "x.txt")]) == 2


def test_mock_vehicle_flies_with_telemetry_after_upload():
    """A vehicle with a landmark database flies what it stored and says so over MAVLink."""
    import numpy as np

    from gcs_planner.link.connection import open_link
    from gcs_planner.link.mission_client import MissionClient
    from gcs_planner.link.params import set_parameter
    from gcs_planner.mission.items import MissionItem
    from gcs_planner.scenario.generate import DATASET1
    from gcs_planner.scenario.georef import LocalFrame
    from gcs_planner.scenario.model import Kind, Scenario

    xyz = np.array([[i * 12_000.0, 0.0, 5000.0] for i in range(5)])
    sc = Scenario(
        ids=("A", "V1", "H1", "V2", "B"),
        xyz=xyz,
        kind=np.array([Kind.A, Kind.V, Kind.H, Kind.V, Kind.B], dtype=np.uint8),
        unreliable=np.zeros(5, bool),
        params=DATASET1,
        origin=Origin(30.5, 123.5, 0.0),
    )
    frame = LocalFrame(sc.origin)
    items = []
    for p in xyz:
        lat, lon, alt = frame.to_geodetic(*p)
        items.append(MissionItem(len(items), 0, 16, x=round(lat * 1e7), y=round(lon * 1e7), z=alt))
    # PX4 switches to the next waypoint at its path controller's switch distance (npfg, ~56 m
    # at 25 m/s) and never overflies a last one it turns away from: a run-out point 2 km past B
    # makes it fly over B.
    lat, lon, alt = frame.to_geodetic(xyz[-1][0] + 2000.0, 0.0, xyz[-1][2])
    items.append(MissionItem(len(items), 0, 16, x=round(lat * 1e7), y=round(lon * 1e7), z=alt))
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", scenario=sc) as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link)
            client.connect(5.0)
            client.upload_verified(items)
            # PX4 counts a fixed-wing waypoint reached within NAV_ACC_RAD (10 m by default) and
            # the mission ends at B: to overfly B within the 5 m capture radius it must be less.
            set_parameter(link, client._target(), "NAV_ACC_RAD", 1.0)
            report = vehicle.fly(seed=0, time_scale=None, position_messages=20)
            seen: dict[str, list] = {}
            deadline = time.monotonic() + 1.0
            while time.monotonic() < deadline:
                msg = link.recv(0.05)
                if msg is not None:
                    seen.setdefault(msg.get_type(), []).append(msg)
        finally:
            link.close()
    assert report.arrived
    assert [c.id for c in report.run.corrections] == ["V1", "H1", "V2"]
    assert sorted({m.seq for m in seen["MISSION_ITEM_REACHED"]}) == [0, 1, 2, 3, 4]
    fixes = [m.text for m in seen["STATUSTEXT"]]
    assert sum("fix" in t for t in fixes) == 3
    assert 1 <= len(seen["GLOBAL_POSITION_INT"]) <= 25  # rate-limited, not one per metre
    assert seen["ATTITUDE"] and seen["VFR_HUD"]
    armed = [m for m in seen["HEARTBEAT"] if m.base_mode & 128]
    assert armed and all(m.custom_mode == (4 << 16) | (4 << 24) for m in armed)  # AUTO MISSION


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_benchmark_function_runs(flavour):
    from benchmarks.upload import benchmark_upload

    result = benchmark_upload(200, flavour)
    assert result["items"] == 200 and result["seconds"] > 0
