"""A contingency policy switched on board, flown end to end on the hand-made scenario of
tests/support/policy_scenario.py (8 km of straight legs; the primary is lost when the fix at
P2 fails, the branch over V3 arrives): the mock ArduPilot with policy.lua and the ground link
cut after take-off (`dry-run --policy --onboard`, gcs_planner/policies/onboard_dry_run.py), and
a companion on a PX4 mock's link over UDP loopback (`fly --onboard`,
gcs_planner/policies/companion.py)."""

from __future__ import annotations

import json
import threading
import time

import pytest
from gcs_planner.sim.live_flight import passed_within
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from support.policy_scenario import policy_missions, policy_scenario, write_scenario
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.cli import main
from gcs_planner.core.switch_room import DEFAULT_SWITCH_TIME_S, ONBOARD_SWITCH_TIME_S
from gcs_planner.errors import InputError
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.mission.onboard_applet import applet_text, point_codes
from gcs_planner.mission.onboard_mission import onboard_mission
from gcs_planner.policies.flight import start_mission
from gcs_planner.policies.onboard_dry_run import check_onboard, onboard_dry_run

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

CAPTURE = 5.0


def _applet(scenario, policy) -> str:  # noqa: ANN001 - test helpers
    return applet_text(onboard_mission(policy), point_codes(scenario.ids), "test")


def test_the_applet_switches_to_the_branch_with_the_ground_link_cut() -> None:
    scenario = policy_scenario(0.0)  # every fix at P2 fails
    policy = policy_missions(scenario)
    report = onboard_dry_run(
        policy, scenario, _applet(scenario, policy), runs=2, probability=1.0,
        capture_radius=CAPTURE, navigate_on_estimate=False,
    )  # fmt: skip
    assert report.onboard and report.successes == 2 and report.ok
    for run in report.runs:
        assert run.missions_flown == ("primary", "after-P2") and run.points_met == (
            "H1",
            "P2",
            "V3",
        )
    # Without the applet's switch the same flights are lost: it is what flew them.
    idle = onboard_dry_run(policy, scenario, "return", runs=1, capture_radius=CAPTURE,
                           navigate_on_estimate=False)  # fmt: skip
    assert idle.successes == 0 and idle.runs[0].missions_flown == ("primary",)


def test_nothing_reaches_the_ground_station_after_take_off() -> None:
    scenario = policy_scenario(0.0)
    policy = policy_missions(scenario)
    port = free_udp_port()
    vehicle = MockVehicle(f"udpin:127.0.0.1:{port}", scenario=scenario, live=True,
                          navigate_on_estimate=False)  # fmt: skip
    vehicle.applet = _applet(scenario, policy)
    heard: list[str] = []
    with vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, timeout=0.5, retries=5, transfer="mission")
            client.connect(10.0)
            client.upload_verified(onboard_mission(policy).mission.items)
            start_mission(client)
            vehicle.cut_link()
            vehicle._fly_thread.join(60.0)
            end = time.monotonic() + 1.5  # a heartbeat's period and more
            while time.monotonic() < end:
                msg = link.recv(0.1)
                if msg is not None and msg.get_type() != "BAD_DATA":
                    heard.append(msg.get_type())
        finally:
            link.close()
    live = vehicle.last_live
    assert live.arrived and live.jumps and vehicle.link_cut
    assert any("after-P2" in text for text in vehicle.statustexts)  # said, but not sent
    assert "STATUSTEXT" not in heard and "GLOBAL_POSITION_INT" not in heard
    misses = passed_within(live.track, scenario, ["V3", "B4"], CAPTURE)
    assert max(misses.values()) <= CAPTURE


def test_an_applet_that_calls_what_the_mock_does_not_provide_stops_and_is_named() -> None:
    scenario = policy_scenario(1.0)
    policy = policy_missions(scenario)
    applet = (
        "local function f()\n  local at = ahrs:get_location()\n  return f, 100\nend\nreturn f, 100"
    )
    report = onboard_dry_run(policy, scenario, applet, runs=1, capture_radius=CAPTURE)
    (run,) = report.runs
    assert not run.arrived and run.link_failed and "ahrs" in run.why


def test_plan_writes_the_onboard_files_and_dry_run_flies_them(tmp_path, capsys, monkeypatch):
    toml = write_scenario(tmp_path, p_success=0.5)
    out = tmp_path / "out"
    leave_pictures_undrawn(monkeypatch)  # the onboard files and their flight are the subject
    rc = main(["plan", str(toml), "--policy", "--out", str(out), "--min-probability", "0",
               "--allow-risky"])  # fmt: skip
    assert rc == 0
    for name in ("onboard.plan", "onboard.waypoints", "policy.lua"):
        assert (out / name).is_file()
    data = json.loads((out / "policy.json").read_text())
    assert data["onboard"]["applet"] == "policy.lua" and data["onboard"]["switches"]
    # Straight legs keep no switch room; with turns the default is the onboard switch time.
    assert "switch_room" not in data and DEFAULT_SWITCH_TIME_S == ONBOARD_SWITCH_TIME_S == 1.0
    capsys.readouterr()
    rc = main(["dry-run", str(toml), "--policy", str(out / "policy.json"), "--onboard",
               "--runs", "3", "--navigate-on-truth"])  # fmt: skip
    said = capsys.readouterr()
    assert rc == 0, said.err
    assert "switched on board by its applet" in said.out and "policy.lua" in said.err


def test_an_autopilot_without_applets_is_sent_to_the_companion(tmp_path, capsys) -> None:
    policy = policy_missions(policy_scenario(), firmware="px4")
    with pytest.raises(InputError, match="fly --onboard"):
        check_onboard(policy, "policy.json")
    toml = write_scenario(tmp_path)
    assert main(["dry-run", str(toml), "--onboard", "--runs", "1"]) == 2
    assert "--onboard" in capsys.readouterr().err  # only with --policy


@pytest.fixture
def px4_policy_file(monkeypatch, tmp_path):
    """policy.json on disk whose missions are the hand-made PX4 ones (read_policy stands in)."""
    from gcs_planner.mission import policy_file as real

    policy = policy_missions(policy_scenario(0.0), firmware="px4")
    path = tmp_path / "policy.json"
    path.write_text(json.dumps({"format": real.FORMAT, "version": real.VERSION}))
    monkeypatch.setattr(real, "read_policy", lambda _path: policy)
    return str(path), policy


def test_the_companion_switches_a_px4_mock_on_its_local_link(px4_policy_file, capsys) -> None:
    path, policy = px4_policy_file
    scenario = policy_scenario(0.0)
    port = free_udp_port()
    vehicle = MockVehicle(f"udpin:127.0.0.1:{port}", scenario=scenario, flavour="px4",
                          live=True, speedup=40.0, navigate_on_estimate=False)  # fmt: skip
    with vehicle:
        # PX4 counts a waypoint reached at npfg's switch distance (~56 m here) and would cut the
        # corner at V3 (tests/policies/test_policy_flight.py): a tighter tuning overflies it.
        for name, value in {"NAV_ACC_RAD": 1.0, "NPFG_SW_DST_MLT": 0.1, "NPFG_PERIOD": 2.0}.items():
            vehicle.params.table[name] = (value, vehicle.params.table[name][1])
        rc = main(["fly", path, "--onboard", "--start", "--connect", f"udpout:127.0.0.1:{port}"])
        vehicle._fly_thread.join(60.0)
    said = capsys.readouterr().out
    assert rc == 0, said
    assert "uploaded and verified the onboard mission" in said
    assert "P2 failed: item" in said and "flown: primary -> after-P2" in said
    live = vehicle.last_live
    assert live.arrived and live.points_met == ("H1", "P2", "V3")
    held = [it.command for it in vehicle.mission]
    assert len(held) == len(onboard_mission(policy).mission.items), held


def test_a_restarted_companion_finds_the_onboard_mission_held(px4_policy_file, capsys) -> None:
    path, policy = px4_policy_file
    port = free_udp_port()
    vehicle = MockVehicle(f"udpin:127.0.0.1:{port}", scenario=policy_scenario(0.0),
                          flavour="px4", live=True, speedup=40.0)  # fmt: skip
    with vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, timeout=0.5, retries=5, transfer="mission")
            client.connect(10.0)
            client.upload_verified(onboard_mission(policy).mission.items)
        finally:
            link.close()
        done: list[int] = []
        fly = threading.Thread(target=lambda: done.append(main(
            ["fly", path, "--onboard", "--start-wait", "2", "--connect",
             f"udpout:127.0.0.1:{port}"])))  # fmt: skip
        fly.start()
        fly.join(30.0)
    said = capsys.readouterr()
    assert "holds the onboard mission" in said.out and "uploaded" not in said.out
    assert done == [4]  # nobody started it: the companion says so after --start-wait
