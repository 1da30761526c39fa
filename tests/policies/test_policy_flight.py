"""The ground station in the loop flying a contingency policy (gcs_planner/policies/flight.py,
`gcs-planner fly`, `dry-run --policy`) against the live mock vehicle (sim/live_vehicle.py) over
UDP loopback: it switches to the branch when the fix at P fails and the vehicle overflies the
branch's point; with every fix made it stays on the primary; under 5 % link loss; a branch that
cannot be uploaded leaves a whole mission on the vehicle; a silent vehicle is noticed.

The scenario (tests/support/policy_scenario.py) is 8 km of straight legs: the primary is lost
when the fix at P fails, the branch arrives. The vehicle flies 20 simulated seconds per wall
second where the ground station may act (after the report at P: the 4 km to B, some 6 s of wall
time); elsewhere, with nothing for it to do, in the dry run's time warp (CRUISE), as
`dry-run --policy --cruise-time-scale` flies (sim/live_vehicle.py).
"""

from __future__ import annotations

import json
import threading
from dataclasses import replace

import pytest
from gcs_planner.sim.live_flight import passed_within
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from support.policy_scenario import policy_missions, policy_scenario, write_scenario
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.cli import main
from gcs_planner.link.connection import open_link
from gcs_planner.link.correction_report import format_report, parse_report
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import mission_differences
from gcs_planner.mission.policy_missions import PolicyMissions
from gcs_planner.policies.flight import PolicyFlight

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

SCALE = 20.0
# The flights whose verdict hangs on a switch made in time fly slower: the window after the
# report at P (until the aircraft passes abeam V2, 2 km on) is then 8 s of wall time.
SWITCH_SCALE = 10.0
# The time scale while no failed or missed fix awaits the ground station: the take-off and the
# legs up to P (and, with every fix made, the whole flight) take a fraction of a second of wall
# time; from a failed fix on, the vehicle flies at the honest scale until the switch has settled.
CRUISE = 1000.0
CAPTURE = 5.0


@pytest.fixture
def policy_file(monkeypatch, tmp_path):
    """policy.json on disk (its format, version and probability) and the missions read from it:
    the hand-made ones of ``policy_missions``."""
    from gcs_planner.mission import policy_file as real

    held: dict[str, PolicyMissions] = {}

    def provide(policy: PolicyMissions, probability: float | None = None,
                room: float | None = None):  # fmt: skip
        path = tmp_path / "policy.json"
        data: dict = {"format": real.FORMAT, "version": real.VERSION}
        if probability is not None:
            data["value"] = {"probability": probability}
        if room is not None:
            data["switch_room"] = {"distance_m": room}
        path.write_text(json.dumps(data))
        held[str(path)] = policy
        return str(path)

    # The missions come from this file's hand-made policy, not from a whole policy.json
    # (tests/mission/test_policy_missions.py and the end-to-end test below read real ones).
    monkeypatch.setattr(real, "read_policy", lambda path: held[str(path)])
    return provide


def _holds(vehicle: MockVehicle, items, firmware: str) -> bool:
    return not mission_differences(list(items), vehicle.mission, skip_home=firmware == "ardupilot")


def _fly(p_success: float, loss: float = 0.0, scale: float = SCALE):
    scenario = policy_scenario(p_success)
    policy = policy_missions(scenario)
    port = free_udp_port()
    faults = None
    if loss:
        from gcs_planner.sim.faults import FaultRates

        faults = FaultRates(drop=loss)
    vehicle = MockVehicle(
        f"udpin:127.0.0.1:{port}", scenario=scenario, live=True, speedup=scale,
        navigate_on_estimate=False, faults_in=faults, faults_out=faults, fault_seed=5,
        cruise_speedup=CRUISE,
    )  # fmt: skip
    vehicle.watch_points = frozenset(s.point for s in policy.switches)
    lines: list[str] = []
    with vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, timeout=0.5, retries=5, transfer="mission")
            client.connect(10.0)
            outcome = PolicyFlight(client, policy, say=lines.append).run(start=True)
        finally:
            link.close()
        vehicle._fly_thread.join(60.0)
    return scenario, policy, vehicle, outcome, lines


def test_reports_are_read_robustly():
    text = format_report("V", "P2", "FAILED", "v20.0 h10.0")
    assert parse_report(text) == parse_report(text.encode()) and parse_report(text).no_fix
    assert parse_report("H fix 13 MISSED by 12.3m").no_fix  # the replayed flight's words
    assert parse_report("V fix 7 made").took and not parse_report("V fix 7 LOST").no_fix
    for other in (
        "PreArm: Bad GPS",
        "V fix",
        "V fix 12",
        "X fix 12 made",
        "V fix 12 MAYBE",
        "V fix 12 madeX",
        "V fix 1 2 made",
        b"V fix \xff made",
        None,
        42,
        "",
    ):
        assert parse_report(other) is None, other  # fmt: skip
    with pytest.raises(ValueError):
        format_report("V", "two words", "made")


def test_the_ground_station_switches_to_the_branch_when_the_fix_fails():
    scenario, policy, vehicle, outcome, lines = _fly(p_success=0.0, scale=SWITCH_SCALE)
    assert outcome.missions_flown == ("primary", "after-P2") and outcome.switches == 1
    assert _holds(vehicle, policy.missions["after-P2"].items, "ardupilot")
    live = vehicle.last_live
    assert live.points_met == ("H1", "P2", "V3") and live.arrived
    misses = passed_within(vehicle.last_live.track, scenario, ["V3", "B4"], CAPTURE)
    assert max(misses.values()) <= CAPTURE
    assert any("item 5 current (confirmed)" in line for line in lines)


def test_with_every_fix_made_it_stays_on_the_primary():
    scenario, policy, vehicle, outcome, _ = _fly(p_success=1.0)
    assert outcome.missions_flown == ("primary",) and outcome.switches == 0
    assert _holds(vehicle, policy.missions["primary"].items, "ardupilot")
    assert vehicle.last_live.points_met == ("H1", "P2") and vehicle.last_live.arrived
    # V3 is 300 m off the primary's leg: never overflown
    assert passed_within(vehicle.last_live.track, scenario, ["V3"], CAPTURE)["V3"] > 250


def test_dry_run_of_the_policy_under_5_percent_loss(policy_file, tmp_path, capsys):
    toml = write_scenario(tmp_path, p_success=0.0)
    path = policy_file(policy_missions(policy_scenario(0.0)), probability=1.0)
    rc = main(["dry-run", str(toml), "--policy", path, "--runs", "2", "--loss", "0.05",
               "--time-scale", str(SWITCH_SCALE), "--cruise-time-scale", "1000",
               "--navigate-on-truth", "--json"])  # fmt: skip
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["ok"] and d["successes"] == 2 and d["probability_within_ci"]
    assert [r["missions_flown"] for r in d["runs"]] == [["primary", "after-P2"]] * 2
    assert all(r["points_met"] == ["H1", "P2", "V3"] for r in d["runs"])


def test_dry_run_of_the_policy_measures_its_switches_against_the_room(policy_file, tmp_path,
                                                                     capsys):  # fmt: skip
    """Each switch's distance from its fix is reported; a room smaller than it is warned of.
    The parameters given are set on the vehicle before the upload: one it lacks fails the run."""
    toml = write_scenario(tmp_path, p_success=0.0)
    path = policy_file(policy_missions(policy_scenario(0.0)), probability=1.0, room=1.0)
    rc = main(["dry-run", str(toml), "--policy", path, "--runs", "1", "--time-scale",
               str(SWITCH_SCALE), "--cruise-time-scale", "1000", "--navigate-on-truth",
               "--param", "TECS_CLMB_MAX=9", "--json"])  # fmt: skip
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["successes"] == 1 and d["switch_room"] == 1.0
    [[point, metres]] = d["runs"][0]["switches"]
    # told as the track leaves the 5 m capture radius, switched within the 2 km to V3
    assert point == "P2" and CAPTURE <= metres < 2000.0 and d["longest_switch_m"] == metres
    assert d["switches_beyond_room"] == 1
    rc = main(["dry-run", str(toml), "--policy", path, "--runs", "1", "--time-scale",
               str(SWITCH_SCALE), "--cruise-time-scale", "1000",
               "--navigate-on-truth"])  # fmt: skip
    out = capsys.readouterr().out
    assert rc == 0 and "1 switch(es) set current, the farthest" in out
    assert "WARNING: 1 switch(es) beyond the switch room" in out
    rc = main(["dry-run", str(toml), "--policy", path, "--runs", "1", "--param",
               "NO_SUCH_PARAM=1", "--timeout", "0.2"])  # fmt: skip
    assert rc == 4 and "NO_SUCH_PARAM" in capsys.readouterr().out


def _unsendable(policy: PolicyMissions, command: int) -> PolicyMissions:
    """The policy with a branch item after the failed point that the vehicle refuses."""
    branch = policy.missions["after-P2"]
    items = list(branch.items)
    items[6] = replace(items[6], command=command)
    missions = {**policy.missions, "after-P2": replace(branch, items=tuple(items))}
    return replace(policy, missions=missions)


@pytest.mark.parametrize(
    ("firmware", "refused", "said"),
    [
        # ArduPilot wrote items 0-5 in place before refusing item 6: the ground station finds
        # the mix on reading back and uploads the primary again.
        ("ardupilot", 5000, "uploaded again and verified"),
        # PX4 refuses NAV_LOITER_TURNS and never left the mission it flies.
        ("px4", 18, "whole (read back)"),
    ],
)
def test_a_branch_that_cannot_be_uploaded_leaves_a_whole_mission(
    policy_file, capsys, firmware, refused, said
):
    scenario = policy_scenario(0.0)
    policy = _unsendable(policy_missions(scenario, firmware), refused)
    path = policy_file(policy)
    port = free_udp_port()
    vehicle = MockVehicle(f"udpin:127.0.0.1:{port}", scenario=scenario, flavour=firmware,
                          live=True, speedup=SCALE, navigate_on_estimate=False,
                          cruise_speedup=CRUISE)  # fmt: skip
    vehicle.watch_points = frozenset(s.point for s in policy.switches)
    with vehicle:
        rc = main(["fly", path, "--connect", f"udpout:127.0.0.1:{port}", "--start",
                   "--transfer", "mission", "--timeout", "0.5", "--quiet"])  # fmt: skip
        out, err = capsys.readouterr()
        assert rc == 4
        assert _holds(vehicle, policy.missions["primary"].items, firmware)
    assert "V fix P2 FAILED" in out and "Traceback" not in err
    assert err.count("\n") == 1 and "mission 'after-P2' could not be uploaded" in err
    assert said in err and "'primary'" in err


def test_a_vehicle_that_stops_reporting_is_noticed(policy_file, capsys):
    scenario = policy_scenario(0.0)
    path = policy_file(policy_missions(scenario))
    port = free_udp_port()
    vehicle = MockVehicle(f"udpin:127.0.0.1:{port}", scenario=scenario, live=True,
                          speedup=SCALE, navigate_on_estimate=False)  # fmt: skip

    def fall_silent() -> None:
        # Once the flight is under way the vehicle falls silent: no heartbeat, no telemetry.
        # (Its link cut, not its loop stopped: a stopped flight says disarmed as it ends.)
        while not vehicle.flying:
            if vehicle._stop.wait(0.05):
                return
        vehicle.cut_link()

    with vehicle:
        watcher = threading.Thread(target=fall_silent, daemon=True)
        watcher.start()
        rc = main(["fly", path, "--connect", f"udpout:127.0.0.1:{port}", "--start",
                   "--silence", "2", "--timeout", "0.5", "--quiet"])  # fmt: skip
        watcher.join(10.0)
    out, err = capsys.readouterr()
    assert rc == 4 and "the vehicle stopped reporting" in err and "Traceback" not in err
    assert "uploaded and verified mission 'primary'" in out


def test_a_policy_whose_branch_differs_before_the_failed_point_is_refused(policy_file, capsys):
    policy = policy_missions(policy_scenario())
    branch = policy.missions["after-P2"]
    items = list(branch.items)
    items[3] = replace(items[3], z=items[3].z + 50.0)  # H1's waypoint moved
    bad = replace(policy, missions={**policy.missions,
                                    "after-P2": replace(branch, items=tuple(items))})  # fmt: skip
    rc = main(["fly", policy_file(bad), "--connect", "udpout:127.0.0.1:9"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    assert "switches[0]" in err and "differs from 'primary' before the failed point" in err


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_a_landmark_passed_outside_the_capture_radius_is_reported_missed(flavour):
    """PX4 counts a waypoint reached at its switch distance (~56 m) and cuts the corner at P and
    at V3 on the branch; ArduPilot, accepting at 1 m, overflies both."""
    import numpy as np
    from gcs_planner.sim.guidance import AutopilotParams
    from gcs_planner.sim.live_flight import LiveFlight

    scenario = policy_scenario(0.0)
    items = policy_missions(scenario, flavour).missions["after-P2"].items
    flight = LiveFlight(items, scenario, flavour=flavour, profile=scenario.vehicle,
                        autopilot=AutopilotParams(flavour, loiter_radius=0.0),
                        capture_radius=CAPTURE, rng=np.random.default_rng(1))  # fmt: skip
    fixes, missed = [], []
    t = 0.0
    while flight.going and t < 600.0:
        t += 5.0
        happened = flight.fly_until(t)
        fixes += [c.id for c in happened.corrections]
        missed += [(m.id, m.kind, m.miss) for m in happened.missed]
    if flavour == "ardupilot":
        assert fixes == ["H1", "P2", "V3"] and missed == []
    else:
        assert fixes == ["H1"] and [m[:2] for m in missed] == [("P2", "V"), ("V3", "V")]
        assert all(m[2] > CAPTURE for m in missed)
        assert parse_report(format_report("V", "P2", "MISSED", f"by {missed[0][2]:.1f}m")).no_fix


@pytest.mark.parametrize(
    ("change", "said"),
    [
        ("reliable point", "point V3 is reliable in policy: its fix cannot fail"),
        ("moved point", "is 300 m from point P2 of policy: the policy is not for this scenario"),
    ],
)
def test_dry_run_refuses_a_policy_not_for_its_scenario(policy_file, tmp_path, capsys, change,
                                                       said):  # fmt: skip
    toml = write_scenario(tmp_path)
    policy = policy_missions(policy_scenario())
    (switch,) = policy.switches
    if change == "reliable point":
        policy = replace(policy, switches=(replace(switch, point="V3"),))
    else:  # the vehicle's database has P 300 m north of where the missions put it
        rows = (tmp_path / "points.csv").read_text().replace("P2,4000.0,0.0", "P2,4000.0,300.0")
        (tmp_path / "points.csv").write_text(rows)
    rc = main(["dry-run", str(toml), "--policy", policy_file(policy), "--runs", "1"])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and said in err and "switches[0]" in err


def test_plan_policy_then_dry_run_it_end_to_end(tmp_path, capsys, monkeypatch):
    """The exporter's policy.json read by the dry run (no stand-in): planned where P's fix
    takes half the time (the shortest route passes P and is replanned on failure to V3), then
    flown twice where every fix fails, through the mid-flight switch at 5 % loss."""
    (tmp_path / "plan").mkdir()
    (tmp_path / "fly").mkdir()
    planned = write_scenario(tmp_path / "plan", p_success=0.5)
    flown = write_scenario(tmp_path / "fly", p_success=0.0)
    out = tmp_path / "out"
    leave_pictures_undrawn(monkeypatch)  # policy.json and its flight are the subject here
    rc = main(["plan", str(planned), "--choose", "shortest", "--min-probability", "0",
               "--out", str(out), "--policy"])  # fmt: skip
    assert rc == 0
    assert "switch: primary item" in capsys.readouterr().out
    rc = main(["dry-run", str(flown), "--policy", str(out / "policy.json"), "--runs", "2",
               "--loss", "0.05", "--time-scale", str(SWITCH_SCALE), "--cruise-time-scale",
               str(CRUISE), "--navigate-on-truth", "--json"])  # fmt: skip
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["successes"] == 2, d
    assert d["probability"] == 1.0
    assert [r["missions_flown"] for r in d["runs"]] == [["primary", "branch-P2"]] * 2
    assert all("V3" in r["points_met"] for r in d["runs"])
