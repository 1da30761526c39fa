"""`plan --from-state`: the continuation from a state mid-flight on the command line."""

from __future__ import annotations

import json

import numpy as np
from support.scenarios import flags_of, write_scenario_csv

from gcs_planner.cli import main
from gcs_planner.core.from_state import FlightState, compass_heading, state_scenario
from gcs_planner.core.planner import plan
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Kind, Parameters


def _scenario():
    params = Parameters(30, 30, 30, 30, 30, 0.001, turn_radius=300.0, p_success=0.8)
    return random_scenario(9, 4, params=params, box=(50_000, 15_000, 1_000))


def test_plan_from_a_state_is_the_librarys(tmp_path, capsys) -> None:
    sc = _scenario()
    csv = write_scenario_csv(sc, tmp_path / "sc.csv")
    at = next(j for j in range(sc.n) if int(sc.kind[j]) in (Kind.V, Kind.H))
    flown = next(j for j in range(sc.n) if j != at and int(sc.kind[j]) in (Kind.V, Kind.H))
    state = f"{sc.ids[at]}:4.5,7.25:60"
    args = ["plan", str(csv), *flags_of(sc), "--from-state", state, "--flown", sc.ids[flown]]
    assert main([*args, "--json", "--min-probability", "0"]) == 0
    got = json.loads(capsys.readouterr().out)
    sub, _ = state_scenario(
        sc, FlightState(at, compass_heading(60.0), 4500.0, 7250.0, frozenset({flown}))
    )
    want = plan(sub, min_probability=0.0)
    assert got["scenario"]["initial_errors"] == [4500.0, 7250.0]
    routes = [r["route"] for r in got["front"]]
    assert routes == [list(r.ids()) for r in want.routes]
    assert all(r[0] == sc.ids[at] and sc.ids[flown] not in r for r in routes)
    np.testing.assert_allclose(got["scenario"]["heading_at_a"], compass_heading(60.0))


def test_bad_states_exit_2_naming_the_flag(tmp_path, capsys) -> None:
    sc = _scenario()
    csv = write_scenario_csv(sc, tmp_path / "sc.csv")
    base = ["plan", str(csv), *flags_of(sc)]
    for bad, said in (
        (["--from-state", "nowhere:1,2"], "no point 'nowhere'"),
        (["--from-state", f"{sc.ids[1]}:1"], "two numbers"),
        (["--from-state", f"{sc.ids[1]}:1,-2"], "must be >= 0"),
        (["--from-state", f"{sc.ids[1]}:1,2:north"], "heading must be degrees"),
        (["--from-state", f"{sc.ids[sc.end]}:1,2"], "at B"),
        (["--flown", sc.ids[1]], "--flown needs --from-state"),
        (["--from-state", f"{sc.ids[1]}:1,2", "--flown", "x9"], "no point 'x9'"),
    ):
        assert main([*base, *bad]) == 2, bad
        err = capsys.readouterr().err
        assert said in err and "Traceback" not in err, (bad, err)
