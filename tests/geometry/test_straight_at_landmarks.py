"""Straight at every landmark (docs/model.md): airplane legs with a run-out (straight on from
each point before the turn) and a run-in (a tangent of at least that much into the next point).

What is held here: the leg's geometry (the departure waypoint on the arrival heading, the turn
after it, the tangent's length), the compiled legs against numpy's, the planner's front against
enumeration (the search and the brute force share only the leg model), the compiled search
against the Python one with runs, the mission's departure waypoints, the runs derived from the
autopilot, and that with no runs nothing changes.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import replace

import numpy as np
import pytest
from support import enumeration
from support.compiled_search import assert_compiled_flies_as_python, legs_modes
from support.enumeration import TWO, assert_plans_enumeration, enumerate_fronts
from support.flown_route_memo import remember_flown_routes
from support.scenarios import probed_scenario, tall_scenario
from support.workbook_once import read_workbooks_once

from gcs_planner.aircraft.autopilot import ARDUPLANE, PX4
from gcs_planner.core.planner import plan
from gcs_planner.geometry.airplane import airplane_leg, tangent_lengths
from gcs_planner.geometry.legs import AirplaneLegs, leg_model_of, scenario_leg_model
from gcs_planner.mission.builder import build_mission, resolve_origin
from gcs_planner.mission.items import HELIX_COMMANDS, MAV_CMD_NAV_WAYPOINT
from gcs_planner.mission.plan_json import plan_to_dict
from gcs_planner.scenario.georef import LocalFrame


@pytest.fixture(scope="module", autouse=True)
def routes_flown_once():
    """The enumerations below fly every simple route of each scenario: each leg once for the
    routes that share the partial route before it (support/prefix_flight.py); and the contest
    workbook read once for the module's plans (support/workbook_once.py)."""
    with contextlib.ExitStack() as both:
        both.enter_context(contextlib.contextmanager(read_workbooks_once)())
        yield from remember_flown_routes(enumeration)


def _random_legs(seed: int, m: int = 400):
    rng = np.random.default_rng(seed)
    start = rng.uniform(-500, 500, 3)
    heading = np.array([*rng.normal(size=2), 0.0])
    ends = start + rng.uniform(-4000, 4000, (m, 3)) * [1, 1, 0.1]
    return rng, start, heading, ends


@pytest.mark.parametrize("seed", range(6))
def test_a_leg_runs_out_on_its_heading_then_turns_and_arrives_on_its_run_in(seed: int) -> None:
    rng, start, heading, ends = _random_legs(seed)
    radius = float(rng.choice([50.0, 200.0, 800.0]))
    run_in, run_out = rng.uniform(50, 900, 2)
    model = leg_model_of(radius, "airplane", 15.0, 12.0, run_in, run_out)
    lengths, _ = model.lengths(start, heading, ends)
    u = np.array([heading[0], heading[1], 0.0]) / math.hypot(heading[0], heading[1])
    flat = np.column_stack([ends[:, :2], np.zeros(len(ends))])
    turn_start = np.array([start[0], start[1], 0.0]) + run_out * u
    tangents = tangent_lengths(turn_start, u, flat, radius)
    assert np.all(np.isinf(lengths[tangents < run_in]))  # no leg arrives on too short a line
    flown = np.flatnonzero(np.isfinite(lengths))
    assert 0 < len(flown) < len(ends)
    bounds = model.lower_bounds(start, ends)
    assert np.all(bounds[flown] <= lengths[flown] * (1 + 1e-12))
    for i in flown[:40]:
        leg = model.leg(start, heading, ends[i])
        assert leg.length == pytest.approx(lengths[i], rel=1e-12)
        # straight on along the arrival heading to the departure point, at the leg's slope
        dep = leg.departure_point
        assert np.allclose(dep[:2], start[:2] + run_out * u[:2], atol=1e-9)
        assert leg.heading_at(0.5 * run_out * leg.length / leg.horizontal_length) == (
            pytest.approx(leg.heading_in)
        )
        # the polyline it samples is as long as the leg and ends on the target
        pts = leg.sample(2.0)
        assert np.allclose(pts[-1], ends[i])
        assert np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1)) == pytest.approx(
            lengths[i], rel=2e-3
        )
        assert leg.straight_horizontal >= run_in - 1e-6
        if leg.centre is not None:  # the turn starts at the departure point
            assert math.hypot(*(leg.centre[:2] - dep[:2])) == pytest.approx(radius)
    # compiled legs: the same lengths and the same legs ruled out
    fast, heads = model.compiled_lengths(start, heading, ends)
    assert np.array_equal(np.isinf(fast), np.isinf(lengths))
    np.testing.assert_allclose(fast[flown], lengths[flown], rtol=1e-12)


def test_a_free_heading_at_a_needs_its_run_in_only() -> None:
    model = AirplaneLegs(200.0, 90.0, 90.0, run_in=300.0, run_out=500.0)
    start = np.zeros(3)
    ends = np.array([[250.0, 0.0, 0.0], [301.0, 0.0, 0.0], [0.0, 2000.0, 10.0]])
    lengths, _ = model.lengths(start, None, ends)
    assert math.isinf(lengths[0])
    assert lengths[1] == pytest.approx(301.0)
    assert lengths[2] == pytest.approx(math.hypot(2000.0, 10.0))
    leg = model.leg(start, None, ends[2])
    assert leg.run_out == 0.0 and leg.departure_point is None


def test_runs_are_only_for_airplane_legs_with_turns() -> None:
    assert leg_model_of(0.0, "airplane", 10.0, 10.0, 300.0, 300.0).kernel_legs().run_in == 0.0
    assert leg_model_of(200.0, "cs3d", 90.0, 90.0, 300.0, 300.0).name == "cs3d"
    straight = leg_model_of(0.0, "airplane", 90.0, 90.0, 300.0, 300.0)
    assert straight.name == "straight"


def _with_runs(scenario, seed: int):
    rng = np.random.default_rng(9_000 + seed)
    return scenario.with_params(
        approach=float(rng.uniform(500, 3000)), departure=float(rng.uniform(300, 2500))
    )


def test_the_front_with_runs_equals_enumeration() -> None:
    """Tall random scenarios (turning radius 400 m, with and without climb limits), runs of
    0.3 to 3 km: the planner's fronts (two and three objectives) equal brute force, and the
    runs change the front in a good share of the sample (they bite)."""
    nonempty = bitten = 0
    for seed in range(14):
        for limited in (False, True):
            # 3 or 4 points (16 or 65 routes), not 4 or 5 (65 or 326): the runs still change
            # 11 fronts of 28.
            base = tall_scenario(seed, "airplane", 400.0, limited, points=(3, 4))
            scenario = _with_runs(base, seed)
            want = assert_plans_enumeration(scenario, f"seed {seed}, {limited=}")
            nonempty += bool(want[TWO])
            bitten += want != enumerate_fronts(base)
    assert nonempty >= 10
    assert bitten >= 8, "the runs must change the front in the sample"


@pytest.mark.parametrize("legs", ["airplane", "airplane, climb limits"])
def test_the_compiled_search_flies_runs_as_the_python_one(monkeypatch, legs: str) -> None:
    """The branch and bound's compiled search (search_kernel: the legs from airplane_kernel with
    the runs in its Legs record) against the Python one, both against depth-first enumeration."""
    modes = legs_modes(monkeypatch)
    for seed in range(6):
        base = probed_scenario(seed, legs)
        scenario = base.with_params(approach=400.0 + 100 * seed, departure=700.0 - 80 * seed)
        assert scenario_leg_model(scenario).kernel_legs().run_out > 0
        assert_compiled_flies_as_python(scenario, (legs, seed))
    assert 2 in modes  # airplane legs flown by the kernel


def test_no_runs_leave_the_legs_as_they_were() -> None:
    rng, start, heading, ends = _random_legs(11)
    a = AirplaneLegs(300.0, 12.0, 14.0)
    b = AirplaneLegs(300.0, 12.0, 14.0, run_in=0.0, run_out=0.0)
    assert np.array_equal(a.lengths(start, heading, ends)[0], b.lengths(start, heading, ends)[0])
    # (the bounds over arrival headings hold with runs too: tests/core/test_proof_pair_runs.py)
    assert a.turns_in_bounds and AirplaneLegs(300.0, run_out=1.0).turns_in_bounds
    leg = airplane_leg(start, heading, ends[0], 300.0, 12.0, 14.0)
    assert leg.run_out == 0.0 and leg.departure_point is None


@pytest.mark.parametrize("firmware", [ARDUPLANE.firmware, PX4.firmware])
def test_the_mission_overflies_each_point_straight_on_to_its_departure_waypoint(
    firmware: str,
) -> None:
    # seed 4 with climb limits: a route whose second leg climbs on a helix after its run-out
    scenario = replace(
        tall_scenario(4, "airplane", 400.0, True).with_params(approach=300.0, departure=600.0),
        heading_at_a=(1.0, 0.0, 0.0),
    )
    result = plan(scenario, objectives=TWO, time_limit=None)
    assert any(s.leg.helix_turns > 0 for s in result.route.stops[1:])
    plan_dict = plan_to_dict(result)
    mission = build_mission(plan_dict, firmware=firmware)
    route = result.route
    seqs = dict(mission.point_seqs)
    items = mission.items
    departures = [it for it in items if it.note.startswith("departure")]
    # every point, A with its given heading included and B before the end action, has one
    assert len(departures) == len(route.points)
    frame_points = {it.seq: it for it in items if it.command == MAV_CMD_NAV_WAYPOINT}
    for pid, seq in list(seqs.items())[:-1]:
        after = items[seq + 1]
        assert after.note.startswith(f"departure {pid}"), (pid, after.note)
        assert seq + 1 in frame_points
    # the plan JSON keeps each leg's run-out
    legs = plan_dict["front"][plan_dict["chosen"]]["legs"]
    assert all(
        leg["geometry"]["run_out"] == pytest.approx(scenario.params.departure) for leg in legs
    )
    # the loiter of a helix is centred one turning radius beside the departure waypoint
    frame = LocalFrame(resolve_origin(plan_dict, None)[0])
    loiters = [it for it in items if it.command in HELIX_COMMANDS]
    assert loiters
    for loiter in loiters:
        before = items[loiter.seq - 1]
        assert before.note.startswith("departure")
        a = frame.to_local(before.x / 1e7, before.y / 1e7, before.z)
        c = frame.to_local(loiter.x / 1e7, loiter.y / 1e7, loiter.z)
        assert math.hypot(a[0] - c[0], a[1] - c[1]) == pytest.approx(400.0, abs=0.05)


def test_b_is_overflown_straight_on_before_the_end_action() -> None:
    scenario = tall_scenario(4, "airplane", 400.0, True).with_params(
        approach=300.0, departure=600.0
    )
    plan_dict = plan_to_dict(plan(scenario, objectives=TWO, time_limit=None))
    for firmware in (ARDUPLANE.firmware, PX4.firmware):
        items = build_mission(plan_dict, firmware=firmware).items
        b_seq = dict(build_mission(plan_dict, firmware=firmware).point_seqs)[
            plan_dict["front"][plan_dict["chosen"]]["route"][-1]
        ]
        after = items[b_seq + 1]
        assert after.command == MAV_CMD_NAV_WAYPOINT and after.note.startswith("departure")
        frame = LocalFrame(resolve_origin(plan_dict, None)[0])
        b = frame.to_local(items[b_seq].x / 1e7, items[b_seq].y / 1e7, items[b_seq].z)
        d = frame.to_local(after.x / 1e7, after.y / 1e7, after.z)
        assert math.hypot(d[0] - b[0], d[1] - b[1]) == pytest.approx(600.0, abs=0.05)
    # without runs the mission ends at B as before
    plain = plan_to_dict(plan(tall_scenario(4, "airplane", 400.0, True), objectives=TWO))
    items = build_mission(plain).items
    assert not any(it.note.startswith("departure") for it in items)


def test_the_mission_flies_at_the_plans_cruise_airspeed() -> None:
    """DO_CHANGE_SPEED is the plan's cruise airspeed unless the caller says otherwise: the plan's
    climb angles were derived for it (a faster aircraft climbs flatter at the same rate)."""
    from gcs_planner.mission.items import MAV_CMD_DO_CHANGE_SPEED

    scenario = tall_scenario(4, "airplane", 400.0, True).with_vehicle(cruise_airspeed=12.0)
    plan_dict = plan_to_dict(plan(scenario, objectives=TWO, time_limit=None))
    assert plan_dict["vehicle"]["cruise_airspeed"] == 12.0

    def speed(mission) -> float:
        (item,) = [it for it in mission.items if it.command == MAV_CMD_DO_CHANGE_SPEED]
        return item.param2

    assert speed(build_mission(plan_dict)) == 12.0
    assert speed(build_mission(plan_dict, cruise_speed=18.0)) == 18.0
    del plan_dict["vehicle"]["cruise_airspeed"]  # a plan file of an earlier release
    assert speed(build_mission(plan_dict)) == 25.0


DS1 = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
       "--delta", "0.001"]  # fmt: skip


def _plan_json(capsys, dataset_paths, *extra) -> dict:
    import json

    from gcs_planner.cli import main

    rc = main(["plan", str(dataset_paths[1]), *DS1, "--json", "--quiet", *extra])
    out = capsys.readouterr().out
    assert rc == 0
    return json.loads(out)


def test_the_runs_are_derived_from_the_autopilot_and_stated(capsys, dataset_paths) -> None:
    from gcs_planner.aircraft.autopilot import effective

    px4 = _plan_json(capsys, dataset_paths, "--autopilot", PX4.firmware, "--wind", "5")
    env = px4["vehicle"]["envelope"]
    # npfg's track error bound at the largest ground speed: NPFG_PERIOD * NPFG_DAMPING * (V + W)
    want = effective(PX4.firmware, {}).settle_distance(env["tas"] + 5.0)
    assert want == pytest.approx(10.0 * 0.7 * (env["tas"] + 5.0))
    assert px4["parameters"]["approach"] == pytest.approx(want)
    assert px4["parameters"]["departure"] == pytest.approx(want)
    assert env["approach_m"] == pytest.approx(want) and "npfg" in env["runs_source"]
    assert "straight at every landmark" in px4["vehicle"]["description"]
    ardu = _plan_json(capsys, dataset_paths, "--autopilot", ARDUPLANE.firmware)
    v = ardu["vehicle"]["envelope"]["tas"]
    assert ardu["parameters"]["approach"] == pytest.approx(17.0 * 0.75 * v / math.pi)
    # stated: the flags win
    stated = _plan_json(
        capsys, dataset_paths, "--autopilot", PX4.firmware, "--approach", "0", "--departure", "120"
    )
    assert stated["parameters"]["approach"] == 0.0
    assert stated["parameters"]["departure"] == 120.0
    assert stated["vehicle"]["envelope"]["runs_source"] == "stated"
    # the envelope stated directly (the contest's model): no runs, as before
    contest = _plan_json(capsys, dataset_paths, "--turn-radius", "200")
    assert contest["parameters"]["approach"] == 0.0 and contest["vehicle"]["envelope"] is None


def test_a_bad_run_length_names_its_flag(capsys, dataset_paths) -> None:
    from gcs_planner.cli import main

    for flag in ("--approach", "--departure"):
        for bad in ("-5", "nan", "inf"):
            rc = main(["plan", str(dataset_paths[1]), *DS1, flag, bad, "--quiet"])
            err = capsys.readouterr().err
            assert rc == 2 and flag.strip("-") in err and "Traceback" not in err, (flag, bad, err)
