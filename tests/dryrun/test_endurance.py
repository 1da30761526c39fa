"""Endurance in the dry run (gcs_planner/dryrun/endurance.py, sim/guidance.py ``fly``): the
minutes of flight the aircraft has, from ``--endurance`` or the scenario's ``[vehicle]
endurance``; a flight not at B by then is ended by its low-battery failsafe and lost by the
flight, the verdict naming the endurance."""

from __future__ import annotations

import json

import pytest
from gcs_planner.sim.guidance import ENDURANCE_ENDED, fly
from support.flights import FRAME, PROFILE, mission
from support.short_line import short_line

from gcs_planner.aircraft.autopilot import ARDUPLANE
from gcs_planner.cli import main
from gcs_planner.dryrun.endurance import vehicle_endurance
from gcs_planner.dryrun.run import EXIT_LOST
from gcs_planner.errors import InputError


def test_the_flag_wins_over_the_scenarios_vehicle(tmp_path):
    path = short_line(tmp_path, "\n[vehicle]\nendurance = 90\n")
    assert vehicle_endurance(None, path) == 90.0
    assert vehicle_endurance("30", path) == 30.0
    assert vehicle_endurance(None, short_line(tmp_path)) is None
    for bad in ("x", "0", "-5", "inf"):
        with pytest.raises(InputError) as err:
            vehicle_endurance(bad, path)
        assert err.value.field == "--endurance"


def test_a_bad_vehicle_endurance_is_exit_2_naming_the_file_and_key(tmp_path, capsys):
    path = short_line(tmp_path, "\n[vehicle]\nendurance = -1\n")
    assert main(["dry-run", str(path), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "vehicle.endurance" in err and "line.toml" in err


def test_the_flight_ends_where_its_endurance_runs_out():
    items = mission((16, (0, 0, 0), {"param2": 1}), (16, (20000, 0, 0), {"param2": 1}))
    whole = fly(items, FRAME, (0.0, 0.0, 0.0), PROFILE, flavour=ARDUPLANE.firmware)
    short = fly(items, FRAME, (0.0, 0.0, 0.0), PROFILE, flavour=ARDUPLANE.firmware, endurance=300.0)
    assert whole.ended == "mission end" and whole.duration > 300.0
    assert short.ended == ENDURANCE_ENDED and 300.0 <= short.duration < 305.0
    assert short.events[-1].kind == "end" and "endurance" in short.events[-1].text


@pytest.mark.parametrize("truth", [False, True], ids=["estimate", "truth"])
def test_past_the_endurance_every_run_is_lost_by_the_flight_and_named(tmp_path, capsys, truth):
    """The 24 km line takes about 12 minutes in still air, 18 in a 10 m/s headwind: planned for
    still air within 14 minutes, every run flown in the headwind runs out before B, by the
    flight (on the estimate each run flown; on the truth one flight for all), and the verdict
    names the endurance; with the scenario's 60 minutes it arrives. The plan keeps to the
    endurance: 5 minutes is refused before flying, naming it."""
    path = str(short_line(tmp_path, "\n[vehicle]\nendurance = 60\n"))
    argv = ["dry-run", path, "--runs", "3", "--json", "--quiet"]
    argv += ["--navigate-on-truth"] if truth else []
    assert main([*argv, "--endurance", "5"]) == 3
    assert "endurance of 5 min" in capsys.readouterr().err
    rc = main([*argv, "--endurance", "14", "--design-wind", "0", "--wind", "10@90"])
    captured = capsys.readouterr()
    d = json.loads(captured.out)
    assert rc == EXIT_LOST and not d["ok"] and d["verified"]
    assert d["endurance"] == 14.0 and d["flight_losses"] == 3 and d["endurance_losses"] == 3
    assert all("endurance" in r["reason"] for r in d["lost_runs"])
    assert "14 min endurance" in captured.err
    rc = main(argv)
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["ok"] and d["endurance"] == 60.0 and d["endurance_losses"] == 0
