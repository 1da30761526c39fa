"""Endurance in the plan on dataset 1 (issue 52): planned with ArduPlane's shipped envelope
for a 10 m/s wind from 090, its routes need about 6.3 h; 60 minutes is refused (exit 3) naming
the endurance and the least flight time, 420 minutes plans and says the flight time in the plan
JSON and its summary."""

from __future__ import annotations

import json

from support.paths import DATA

from gcs_planner.cli import main

TABLE2 = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30"]
PLAN = ["plan", str(DATA / "dataset1.xlsx"), *TABLE2, "--delta", "0.001"]
ARDUPLANE_10_FROM_90 = ["--autopilot", "ardupilot", "--wind", "10@90"]


def test_an_hour_is_refused_naming_the_endurance_and_the_least_time(capsys):
    assert main([*PLAN, *ARDUPLANE_10_FROM_90, "--endurance", "60"]) == 3
    err = capsys.readouterr().err
    assert "endurance of 60 min" in err and "needs at least" in err


def test_seven_hours_plan_and_the_plan_says_its_flight_time(capsys):
    assert main([*PLAN, *ARDUPLANE_10_FROM_90, "--endurance", "420", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    endurance = d["endurance"]
    assert endurance["minutes"] == 420.0
    assert all(m <= 420.0 for m in endurance["front_flight_minutes"])
    # Long enough that 13 m/s of wind instead of 10 cannot be flown within 420 minutes.
    assert 300.0 < endurance["chosen_flight_minutes"] <= 420.0
    assert main([*PLAN, *ARDUPLANE_10_FROM_90, "--endurance", "420"]) == 0
    assert "within the endurance of 420 min" in capsys.readouterr().out
