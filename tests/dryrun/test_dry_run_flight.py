"""The check that matters: the dry run's vehicle flies with the scenario's vehicle profile
(climb and descent limits included) whatever leg model planned the route, so a route whose
legs break the limits does not "verify and arrive"."""

from __future__ import annotations

import json

import pytest
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.cli import main
from gcs_planner.core.planner import plan
from gcs_planner.dryrun.run import EXIT_LOST, dry_run
from gcs_planner.scenario.readers import load_scenario

DS2 = {"alpha1": 20, "alpha2": 10, "beta1": 15, "beta2": 20, "theta": 20, "delta": 0.001}
LIMITS = {"turn_radius": 200.0, "max_climb_angle": 15.0, "max_descent_angle": 15.0}
FLAGS = [f for k, v in DS2.items() for f in (f"--{k}", str(v))] + [
    "--turn-radius", "200", "--max-climb-angle", "15", "--max-descent-angle", "15",
    "--choose", "most-reliable",
]  # fmt: skip


def _caught(d: dict) -> None:
    """Not verified-and-arrived, and the report says where the flight went wrong."""
    assert d["verified"] is True
    assert d["arrived"] is False and d["ok"] is False
    missed = [r for r in d["rows"] if r["outcome"] == "missed"]
    lost = [r for r in d["rows"] if r["outcome"] == "lost"]
    assert missed or lost or d["why"]
    for r in missed:
        assert r["miss"] > 5.0 and r["point"] in d["why"]  # named, with its 3D miss distance
    assert d["max_deviation"] > 5.0


def test_steep_cs3d_mission_is_caught_by_the_cli(capsys, dataset_paths):
    """cs3d plans legs of up to 73 degrees; a 15 degree aircraft cannot fly them."""
    rc = main(["dry-run", str(dataset_paths[2]), *FLAGS, "--leg-model", "cs3d", "--json"])
    out, err = capsys.readouterr()
    d = json.loads(out)
    assert rc == EXIT_LOST
    _caught(d)
    assert "lost" in err and "missed" in err


@pytest.fixture(scope="module")
def steep_plan(dataset_paths):
    scenario = load_scenario(dataset_paths[2], {**DS2, **LIMITS}).with_vehicle(leg_model="cs3d")
    return plan(
        scenario, objectives=("length", "corrections", "probability"), choice="most-reliable"
    )


def test_steep_cs3d_mission_is_caught_by_a_px4_vehicle(steep_plan, dataset_paths):
    landmarks = load_scenario(dataset_paths[2], {**DS2, **LIMITS})
    report = dry_run(steep_plan, landmarks, flavour="px4", vehicle_as_is=True)
    _caught(report.to_dict())
    # PX4 will not count a waypoint reached off its altitude: it circles there.
    assert report.flown_to_b > report.planned_length or not report.arrived


@pytest.fixture(scope="module")
def airplane_plan(dataset_paths):
    scenario = load_scenario(dataset_paths[2], {**DS2, **LIMITS})  # default: airplane legs
    return plan(
        scenario, objectives=("length", "corrections", "probability"), choice="most-reliable"
    )


def test_airplane_legs_within_15_degrees_need_arduplane_set_up_for_them(
    airplane_plan, dataset_paths
):
    """The default airplane legs respect the 15 degree limits (helices where a leg is too
    steep): 6.5 m/s at 25 m/s. ArduPlane at its shipped TECS_CLMB_MAX 5 m/s cannot climb them
    and is lost by the flight. Set up for them (TECS_CLMB_MAX / TECS_SINK_MAX 11 m/s, the plan's
    angle at the top's true airspeed, and NAVL1_LIM_BANK 45 so loiters keep the planned radius),
    set over the link as a user would, it overflies every planned correction in order on its
    INS estimate, no run is lost by the flight and the success rate keeps the planned
    probability (a floor: planned with the default flight reserve)."""
    landmarks = load_scenario(dataset_paths[2], {**DS2, **LIMITS})
    assert airplane_plan.scenario.vehicle.leg_model == "airplane"
    shipped = dry_run(airplane_plan, landmarks, flavour="ardupilot", runs=20, vehicle_as_is=True)
    assert shipped.verified and shipped.flight_losses > 0 and not shipped.ok
    assert shipped.setup_shortfalls  # what it was not set up for, named
    setup = {"TECS_CLMB_MAX": 11.0, "TECS_SINK_MAX": 11.0, "NAVL1_LIM_BANK": 45.0}
    report = dry_run(airplane_plan, landmarks, flavour="ardupilot", runs=60, set_params=setup)
    assert "climb 11 m/s" in report.autopilot
    assert report.verified and report.corrections_as_planned
    assert not report.missed and all(r.miss <= 5.0 for r in report.rows)
    assert report.runs_flown and report.flight_losses == 0
    assert report.reserve > 0 and report.max_overrun is not None
    assert report.max_overrun <= report.reserve
    low, high = report.success_ci or (0.0, 0.0)
    assert report.planned_probability <= high and report.probability_within_ci and report.ok
    # The seeded flight ends where it is lost (a flight on the estimate stops there): when it
    # arrives it flew the planned length, when not it was chance at an unreliable point.
    if report.arrived:
        assert report.flown_to_b == pytest.approx(report.planned_length, rel=0.01)
    else:
        assert not report.flight_lost


def test_airplane_legs_within_the_limits_are_flown_by_px4_on_its_altitude_loop(
    airplane_plan, dataset_paths
):
    """The same mission on PX4, set up by the plan's setup: it accepts every waypoint ~56 m
    early (npfg's switch distance, NAV_ACC_RAD 1 m notwithstanding), and TECS flies its height
    errors out over FW_T_ALT_TC (5 s), so it comes over every correction point within the 5 m
    capture radius: no run is lost by the flight. (With the mock's former 1 s height loop it
    passed V point 163 about 8 m high, outside the capture radius, and every run was lost.)"""
    landmarks = load_scenario(dataset_paths[2], {**DS2, **LIMITS})
    report = dry_run(airplane_plan, landmarks, flavour="px4", runs=10)
    assert report.verified and report.flight_losses == 0 and not report.missed
    assert "FW_T_ALT_TC" in report.autopilot


def test_the_certain_route_of_dataset_2_at_20_25_degrees_is_lost_by_the_flight(dataset_paths):
    """Climb 20 and descent 25 degrees (8.6 and 10.6 m/s at 25 m/s): dataset 2's certain route
    (planned probability 1, a 60 m reserve) needs more than either autopilot's mission climb
    rate as shipped (ArduPlane 5, PX4 3 m/s): a vehicle left at them misses a correction point
    in every run and is lost by the flight; the dry run no longer says it arrives."""
    limits = {"turn_radius": 200.0, "max_climb_angle": 20.0, "max_descent_angle": 25.0}
    scenario = load_scenario(dataset_paths[2], {**DS2, **limits, "reserve": 60.0})
    certain = plan(
        scenario,
        objectives=("length", "corrections", "probability"),
        choice="most-reliable",
        max_labels=30_000,
    )
    assert certain.route.probability == 1.0 and certain.route.feasible
    assert all(-25.0 - 1e-9 <= s.leg.path_angle <= 20.0 + 1e-9 for s in certain.route.stops[1:])
    landmarks = load_scenario(dataset_paths[2], {**DS2, **limits})
    for flavour in ("ardupilot", "px4"):
        report = dry_run(certain, landmarks, flavour=flavour, runs=6, vehicle_as_is=True)
        assert report.verified and report.flight_losses == 6 and not report.ok, flavour
        assert report.missed


def test_steep_cs3d_mission_is_caught_through_mock_vehicle_and_upload_processes(
    tmp_path, capsys, dataset_paths
):
    """The same as a user runs it: plan and export here, `gcs-planner mock-vehicle` in its own
    process with the workbook as its landmarks and the 15 degree aircraft, `gcs-planner upload`,
    then MAV_CMD_MISSION_START; the vehicle's STATUSTEXTs say what it missed and that it was
    lost."""
    import subprocess
    import sys
    import time

    from gcs_planner.sim.vehicle import free_udp_port

    from gcs_planner.link.connection import mavlink, open_link

    workbook = str(dataset_paths[2])
    out = tmp_path / "steep"
    with pytest.MonkeyPatch.context() as patch:
        leave_pictures_undrawn(patch)  # the mission, its setup and its flight are the subject
        assert main(["plan", workbook, *FLAGS, "--leg-model", "cs3d", "--out", str(out)]) == 0
    mission = tmp_path / "mission.plan"
    assert main(["export", str(out / "plan.json"), "--format", "plan", "--acceptance-radius",
                 "1", "--out", str(mission)]) == 0  # fmt: skip
    capsys.readouterr()
    port = free_udp_port()
    limits = ["--turn-radius", "200", "--max-climb-angle", "15", "--max-descent-angle", "15"]
    scenario = [f for k, v in DS2.items() for f in (f"--{k}", str(v))] + limits
    proc = subprocess.Popen(
        [sys.executable, "-m", "gcs_planner", "mock-vehicle", "--connect",
         f"udpin:127.0.0.1:{port}", "--scenario", workbook, *scenario, "--speedup", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    texts: list[str] = []
    try:
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet", "--wait", "60"]
        # the operator's workflow: the mission with the setup plan --out wrote (the flight
        # then shows that no setup for 15 degrees flies cs3d's steep legs)
        setup = ["--params", str(out / "vehicle.param")]
        assert main(["upload", *setup, str(mission), *conn]) == 0, capsys.readouterr().err
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            deadline = time.monotonic() + 120.0  # generous: ends on the vehicle's last word
            started, asked = False, 0.0
            while time.monotonic() < deadline and not any("INS LOST" in t for t in texts):
                if not started and time.monotonic() - asked > 2.0:
                    asked = time.monotonic()
                    link.send(link.mav.heartbeat_encode(6, 8, 0, 0, 0))
                    link.send(link.mav.command_long_encode(
                        1, 1, mavlink.MAV_CMD_MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0))  # fmt: skip
                msg = link.recv(0.5)
                if msg is None:
                    continue
                kind = msg.get_type()
                if kind == "COMMAND_ACK" and msg.command == mavlink.MAV_CMD_MISSION_START:
                    # The first start is accepted; a repeat while flying is denied (busy).
                    assert started or msg.result == mavlink.MAV_RESULT_ACCEPTED
                    started = True
                elif kind == "STATUSTEXT":
                    texts.append(msg.text)
        finally:
            link.close()
    finally:
        proc.send_signal(2)
        proc.communicate(timeout=60)
    assert any("MISSED" in t for t in texts), texts
    assert any("INS LOST" in t for t in texts), texts


def test_px4_overflies_b_of_a_plan_without_run_outs(capsys):
    """missions/jsbsim states its envelope (no run-outs): PX4 switches to the end action at
    npfg's switch distance, ~100 m before B, and without the exporter's run-out beyond B it
    turned away and passed B 7.9 m off (lost, outside the 5 m capture radius). Now it arrives:
    every correction made and B passed within the capture radius."""
    from support.paths import MISSIONS

    scenario = MISSIONS / "jsbsim" / "scenario.toml"
    rc = main(["dry-run", str(scenario), "--autopilot", "px4", "--json", "--quiet"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["verified"] and d["arrived"] and d["ok"], (d["route"], d["why"])
    assert d["corrections_as_planned"] and d["flown_to_b"] is not None
    # every correction made (an unreliable fix may fail in the seeded draw, overflown all the same)
    assert all(r["outcome"] == "ok" or (r["outcome"] == "failed" and r["unreliable"])
               for r in d["rows"])  # fmt: skip
