"""A contingency policy as missions (mission/policy_build.py), policy.json (policy_file.py) and
`plan --policy`: every outcome path of the policy is flown by the missions and their switches,
each mission flies exactly the legs the policy was evaluated on, branches repeat their parent
item for item up to the failed point, and the file round-trips and refuses what it should."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from support.policies import random_policy
from support.scenarios import contingency_scenario, flags_of, write_scenario_csv
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.cli import main
from gcs_planner.core.bnb import flown_route
from gcs_planner.core.contingency import (
    Policy,
    _fly,
    _start_heading,
    evaluate,
)
from gcs_planner.core.planner import plan
from gcs_planner.core.replan import replan_on_failure
from gcs_planner.errors import InfeasibleError, InputError
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.mission.items import MAV_CMD_NAV_WAYPOINT
from gcs_planner.mission.plan_json import plan_to_dict
from gcs_planner.mission.policy_build import policy_mission_plans, policy_missions
from gcs_planner.mission.policy_file import read_policy, write_policy
from gcs_planner.scenario.model import Kind, Parameters, Scenario


def _outcome_paths(policy: Policy):
    """Every outcome path: (points A..B, [(branching point, fix took?), ...])."""
    if policy.leaf:
        yield list(policy.points), []
        return
    end = policy.points[-1]
    for ok, child in ((True, policy.on_success), (False, policy.on_failure)):
        for pts, outs in _outcome_paths(child):
            yield list(policy.points) + pts[1:], [(end, ok), *outs]


def _ground_station(sc: Scenario, pm, outs) -> str:
    """The mission flown at the end of an outcome path, switching as the ground station does."""
    mission = pm.primary
    for point, ok in outs:
        switch = None if ok else pm.switch_for(mission, sc.ids[point])
        if switch is not None:
            mission = switch.to_mission
    return mission


def _check(sc: Scenario, policy: Policy, pm) -> None:
    """The structural promises of policy_missions."""
    for pts, outs in _outcome_paths(policy):
        flown = pm.missions[_ground_station(sc, pm, outs)]
        assert list(flown.route) == [sc.ids[j] for j in pts]
    all_success = next(iter(_outcome_paths(policy)))[0]
    assert list(pm.missions[pm.primary].route) == [sc.ids[j] for j in all_success]
    for s in pm.switches:
        flown, to = pm.missions[s.mission], pm.missions[s.to_mission]
        assert s.item == flown.seq_of(s.point) == to.seq_of(s.point)
        assert flown.items[: s.item + 1] == to.items[: s.item + 1]  # item for item
        wp = flown.items[s.item]
        assert wp.command == MAV_CMD_NAV_WAYPOINT and wp.note == f"correction {s.point}"
        assert s.resume_item == s.item + 1 < len(to.items)
        # What follows in the branch is its own next leg, towards its next point.
        nxt = to.route[to.route.index(s.point) + 1]
        assert s.resume_item <= to.seq_of(nxt)


def _base_plan(sc: Scenario) -> dict:
    return plan_to_dict(plan(sc, min_probability=0.0))


def _fork_scenario() -> Scenario:
    """A, U1 (unreliable V), U2 (unreliable H), W1, W2, B, loose limits: every path arrives."""
    xy = [(0, 0), (10_000, 0), (20_000, 500), (25_000, 3_000), (25_000, -3_000), (35_000, 0)]
    kinds = [Kind.A, Kind.V, Kind.H, Kind.V, Kind.H, Kind.B]
    params = Parameters(100, 100, 100, 100, 100, 0.001, turn_radius=0.0, p_success=0.7,
                        fail_residual=5.0)  # fmt: skip
    return Scenario(
        ids=("A", "U1", "U2", "W1", "W2", "B"),
        xyz=np.array([[x, y, 1000.0] for x, y in xy]),
        kind=np.array(kinds, dtype=np.uint8),
        unreliable=np.array([False, True, True, False, False, False]),
        params=params,
        name="fork",
    )


def test_branches_of_branches_and_the_same_point_in_two_contexts() -> None:
    sc = _fork_scenario()
    A, U1, U2, W1, W2, B = range(6)
    after_ok = Policy((U1, U2), Policy((U2, B)), Policy((U2, W1, B)))
    after_fail = Policy((U1, U2), Policy((U2, B)), Policy((U2, W2, B)))
    policy = Policy((A, U1), after_ok, after_fail)
    pm = policy_missions(sc, policy, _base_plan(sc))
    _check(sc, policy, pm)
    routes = {name: " ".join(m.route) for name, m in pm.missions.items()}
    assert routes == {
        "primary": "A U1 U2 B",
        "branch-U1": "A U1 U2 B",  # the same track: only the switch at U2 differs
        "branch-U2": "A U1 U2 W2 B",  # U2 fails after U1 failed
        "branch-U2-2": "A U1 U2 W1 B",  # U2 fails after U1 took
    }
    by = {(s.mission, s.point): s.to_mission for s in pm.switches}
    assert by == {
        ("primary", "U1"): "branch-U1",
        ("branch-U1", "U2"): "branch-U2",
        ("primary", "U2"): "branch-U2-2",
    }
    assert not pm.changes_items(pm.switch_for("primary", "U1"))
    assert pm.changes_items(pm.switch_for("primary", "U2"))


def test_a_fixed_route_is_one_mission() -> None:
    sc = _fork_scenario()
    pm = policy_missions(sc, Policy.from_route(sc, (0, 1, 2, 3, 5)), _base_plan(sc))
    assert list(pm.missions) == ["primary"] and pm.switches == ()
    assert " ".join(pm.missions["primary"].route) == "A U1 U2 W1 B"


@pytest.mark.parametrize("firmware", ["ardupilot", "px4"])
def test_random_policies_are_flown_by_their_missions(firmware: str) -> None:
    rng = np.random.default_rng(3)
    branched = 0
    for seed in range(12):
        sc = contingency_scenario(seed, 0.0, lenient=True)
        try:
            base = _base_plan(sc)
        except InfeasibleError:  # no plan dict to build missions from
            continue
        for _ in range(3):
            policy = random_policy(sc, rng)
            pm = policy_missions(sc, policy, base, firmware=firmware)
            _check(sc, policy, pm)
            branched += len(pm.switches) > 1
    assert branched >= 3


def _replanned(seed: int, departure: float = 150.0):
    """Seed 167's chosen route replans at two failed fixes (airplane legs, 300 m radius)."""
    sc = contingency_scenario(seed, 300.0, n_max=10)
    sc = dataclasses.replace(sc, params=dataclasses.replace(sc.params, departure=departure))
    result = plan(sc, min_probability=0.0)
    return sc, result, replan_on_failure(sc, result.route).policy


def _segment_lengths(sc: Scenario, policy: Policy, outs) -> list[float]:
    """One outcome path's leg lengths as the policy evaluator flies them: segment by segment,
    each from the heading the previous one ended with."""
    model = scenario_leg_model(sc)
    heading, node, lengths = _start_heading(sc), policy, []
    outcomes = iter(outs)
    while True:
        legs, heading = _fly(sc, model, node.points, heading)
        lengths += legs
        if node.leaf:
            return lengths
        _, ok = next(outcomes)
        node = node.on_success if ok else node.on_failure


def test_missions_fly_the_legs_the_policy_was_evaluated_on() -> None:
    sc, result, policy = _replanned(167)
    plans, switches = policy_mission_plans(sc, policy, plan_to_dict(result))
    assert len(switches) == 2
    paths = {tuple(pts): outs for pts, outs in _outcome_paths(policy)}
    for path, one in plans:
        evaluated = _segment_lengths(sc, policy, paths[path.points])
        assert [s.leg.length for s in flown_route(sc, path.points).stops[1:]] == evaluated
        assert [leg["length"] for leg in one["front"][0]["legs"]] == evaluated
        assert [leg["geometry"]["length"] for leg in one["front"][0]["legs"]] == evaluated


def test_switches_resume_after_the_failed_points_waypoint() -> None:
    sc, result, policy = _replanned(167)
    pm = policy_missions(sc, policy, plan_to_dict(result))
    _check(sc, policy, pm)
    branches = [s for s in pm.switches if pm.changes_items(s)]
    assert branches
    for s in branches:
        # The run-out: the branch's departure waypoint straight on over the failed point.
        resume = pm.missions[s.to_mission].items[s.resume_item]
        assert resume.note.startswith(f"departure {s.point} ")
    value = evaluate(sc, policy)
    assert value.probability > result.route.probability + 0.2  # 0.274 -> 0.523 here


# ---------------------------------------------------------------------------------------------
# policy.json


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    sc, result, policy = _replanned(167)
    pm = policy_missions(sc, policy, plan_to_dict(result))
    path = tmp_path_factory.mktemp("policy") / "policy.json"
    write_policy(path, sc, policy, pm, evaluate(sc, policy))
    return sc, pm, path


def test_policy_json_round_trips(written) -> None:
    sc, pm, path = written
    assert read_policy(path) == pm
    assert read_policy(path, scenario=sc) == pm
    data = json.loads(path.read_text())
    tree = data["tree"]
    root = tree["nodes"][tree["root"]]
    assert root["points"][0] == sc.ids[sc.start]
    assert data["value"]["probability"] == pytest.approx(evaluate_value(sc, path))


def evaluate_value(sc: Scenario, path: Path) -> float:
    """The probability of the tree the file holds, rebuilt and evaluated again."""
    data = json.loads(path.read_text())
    nodes, index = data["tree"]["nodes"], {pid: i for i, pid in enumerate(sc.ids)}

    def node(k: int) -> Policy:
        d = nodes[k]
        pts = tuple(index[p] for p in d["points"])
        if "on_success" not in d:
            return Policy(pts)
        return Policy(pts, node(d["on_success"]), node(d["on_failure"]))

    return evaluate(sc, node(data["tree"]["root"])).probability


def test_policy_json_refuses_another_scenario(written) -> None:
    sc, _, path = written
    moved = sc.xyz.copy()
    moved[3, 0] += 1.0
    other = dataclasses.replace(sc, xyz=moved)
    with pytest.raises(InputError) as err:
        read_policy(path, scenario=other)
    assert str(path) in str(err.value) and "scenario.points_sha256" in str(err.value)


def _set(data: dict, where: str, value) -> None:
    keys = [
        int(k) if k.isdigit() else k for k in where.replace("]", "").replace("[", ".").split(".")
    ]
    for k in keys[:-1]:
        data = data[k]
    if value is _DELETE:
        del data[keys[-1]]
    else:
        data[keys[-1]] = value


_DELETE = object()


@pytest.mark.parametrize(
    ("where", "value", "field"),
    [
        ("format", "gcs-planner-plan", "format"),
        ("version", 2, "version"),
        ("missions", _DELETE, "missions"),
        ("missions[1].items[4].command", "16", "missions[1].items[4].command"),
        ("missions[0].items[2].seq", 7, "missions[0].items[2].seq"),
        ("missions[0].firmware", "inav", "missions[0].firmware"),
        ("missions[2].point_seqs[1]", ["2", 999], "missions[2].point_seqs[1]"),
        ("primary", "main", "primary"),
        ("switches[0].item", 4, "switches[0].item"),
        ("switches[1].to_mission", "branch-x", "switches[1].to_mission"),
        ("switches[0].outcome", "success", "switches[0].outcome"),
        ("switches[0].resume_item", 1000, "switches[0].resume_item"),
    ],
)
def test_malformed_policy_files_name_the_field(written, tmp_path, where, value, field) -> None:
    _, _, path = written
    data = json.loads(path.read_text())
    _set(data, where, value)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(InputError) as err:
        read_policy(bad)
    assert err.value.file == str(bad) and err.value.field == field
    assert "\n" not in str(err.value)


def test_unreadable_policy_file(tmp_path) -> None:
    bad = tmp_path / "policy.json"
    bad.write_text("{not json")
    with pytest.raises(InputError, match="not a readable policy JSON"):
        read_policy(bad)
    with pytest.raises(InputError, match="no such file"):
        read_policy(tmp_path / "missing.json")


# ---------------------------------------------------------------------------------------------
# plan --policy


def test_plan_policy_writes_every_mission_and_the_file(tmp_path, capsys, monkeypatch) -> None:
    sc, _, _ = _replanned(167)
    csv = write_scenario_csv(sc, tmp_path / "sc.csv")
    out = tmp_path / "out"
    # A random scenario of the contest's model: its unlimited climbs are steeper than any
    # autopilot's limits, so its missions are written only when asked for.
    risky = ["--allow-risky"]
    assert main(["plan", str(csv), *flags_of(sc), "--out", str(out), "--policy"]) == 3
    assert "no ardupilot setup flies this plan" in capsys.readouterr().err
    # The missions, the policy file and the folder are the subject: the five pictures are
    # asked for and stood in by a 1 px PNG (support/undrawn_pictures.py); what they show is
    # test_picture_layout.py's and test_pictures.py's, and `plan --policy --out` draws them for
    # real in README's documented command (tests/docs/test_documented_commands.py).
    asked = leave_pictures_undrawn(monkeypatch)
    assert main(["plan", str(csv), *flags_of(sc), "--out", str(out), "--policy", *risky]) == 0
    assert {"tree_png", "policy_front_png", "route_png", "front_png", "error_budget_png"} <= set(
        asked
    )
    asked.clear()
    text = capsys.readouterr().out
    assert "contingency policy: 3 mission(s), 2 switch(es)" in text
    assert "chosen route 0" in text and "most reliable route" in text
    names = {p.name for p in out.iterdir()}
    for name in ("primary", "branch-2", "branch-5"):
        assert {f"{name}.plan", f"{name}.waypoints"} <= names
    assert {"policy.json", "policy_tree.png", "policy_front.png", "plan.json"} <= names
    pm = read_policy(out / "policy.json")
    assert set(pm.missions) == {"primary", "branch-2", "branch-5"}
    data = json.loads((out / "policy.json").read_text())
    assert data["missions"][0]["files"] == {
        "plan": "primary.plan",
        "waypoints": "primary.waypoints",
    }
    # The primary is the chosen route: the same mission as mission.plan.
    assert json.loads((out / "primary.plan").read_text()) == json.loads(
        (out / "mission.plan").read_text()
    )
    # A second run replaces the folder it wrote (its branch files included).
    assert main(["plan", str(csv), *flags_of(sc), "--out", str(out), "--policy", *risky]) == 0
    assert {"tree_png", "policy_front_png", "route_png"} <= set(asked)


def test_plan_policy_needs_out(tmp_path, capsys) -> None:
    sc = _fork_scenario()
    csv = write_scenario_csv(sc, tmp_path / "sc.csv")
    assert main(["plan", str(csv), *flags_of(sc), "--policy"]) == 2
    assert "--policy" in capsys.readouterr().err


def test_plan_policy_beyond_brute_force_and_bad_levels(tmp_path, capsys, monkeypatch) -> None:
    """15 correction points (beyond brute force and the exact policy front): the branches are
    planned by the planner and the policy front says it is not proven; a bad --policy-levels
    writes nothing and leaves an earlier folder as it was."""
    from gcs_planner.scenario.generate import random_scenario

    params = Parameters(30, 30, 30, 30, 30, 0.001, turn_radius=0.0, p_success=0.8)
    sc = random_scenario(15, 3, params=params, box=(60_000, 20_000, 2_000))
    csv = write_scenario_csv(sc, tmp_path / "big.csv")
    out = tmp_path / "out"
    args = ["plan", str(csv), *flags_of(sc), "--out", str(out), "--policy", "--allow-risky"]
    leave_pictures_undrawn(monkeypatch)  # the branches and the refusal are the subject here
    assert main([*args, "--policy-levels", "2"]) == 0
    printed = capsys.readouterr().out
    assert "policy front (the non-dominated of the front's routes" in printed
    assert (out / "policy.json").exists() and (out / "primary.plan").exists()
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "plan.json").write_text("earlier")
    bad_args = ["plan", str(csv), *flags_of(sc), "--out", str(bad), "--policy"]
    assert main([*bad_args, "--policy-levels", "0"]) == 2
    err = capsys.readouterr().err
    assert "--policy-levels" in err and "Traceback" not in err
    assert [p.name for p in bad.iterdir()] == ["plan.json"]
    assert (bad / "plan.json").read_text() == "earlier"


def test_branch_missions_get_the_capture_check() -> None:
    from gcs_planner.mission.policy_export import _capture_warning

    sc, _, policy = _replanned(167)
    branch = (0, 2, 5, 1, 8, 3, 9)  # branch-5's path
    assert _capture_warning(sc, branch) is None  # 3.4 m of the 5 m radius at worst
    tight = dataclasses.replace(sc, capture_radius=2.0)
    warning = _capture_warning(tight, branch)
    assert warning is not None and "is likely missed" in warning


def test_a_branch_likely_missed_is_exported_only_when_asked(tmp_path, capsys, monkeypatch) -> None:
    from gcs_planner.mission import policy_export

    sc, _, _ = _replanned(167)
    csv = write_scenario_csv(sc, tmp_path / "sc.csv")
    out = tmp_path / "out"
    leave_pictures_undrawn(monkeypatch)  # the refusal and the files are the subject here
    missed = "point 8 is likely missed"
    monkeypatch.setattr(
        policy_export, "_capture_warning", lambda s, pts: missed if 8 in pts else None
    )
    args = ["plan", str(csv), *flags_of(sc), "--out", str(out), "--policy"]
    assert main(args) == 3
    err = capsys.readouterr().err
    assert f"mission branch-5: {missed}" in err and "--allow-risky" in err
    assert not out.exists()
    assert main([*args, "--allow-risky"]) == 0
    assert f"mission branch-5: {missed}" in capsys.readouterr().err
    assert (out / "branch-5.plan").exists()


def test_px4_policy_round_trips(tmp_path) -> None:
    sc, result, policy = _replanned(167)
    pm = policy_missions(sc, policy, plan_to_dict(result), firmware="px4")
    _check(sc, policy, pm)
    assert pm.missions["primary"].items[0].note == "cruise speed"  # no home item on PX4
    path = write_policy(tmp_path / "policy.json", sc, policy, pm, evaluate(sc, policy))
    assert read_policy(path, scenario=sc) == pm
