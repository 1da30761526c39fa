"""The aerosonde flies the coastal mission on JSBSim, planned within its climb (issue 52),
and a mission beyond an airframe is refused before its flight starts, with a report that says
so and lists no misses."""

from __future__ import annotations

import json

# The test extra installs JSBSim: without it these tests fail at import, never skip.
import jsbsim  # noqa: F401
import pytest
from gcs_planner.sim import guidance  # noqa: E402
from gcs_planner.sim.jsbsim_airframe import FlightModel, LegNeed  # noqa: E402
from gcs_planner.sim.navigators.base import NavCommand  # noqa: E402
from support.coast_copy import coast_copy
from support.paths import MISSIONS

from gcs_planner.aircraft.airframe_trim import airframe_trims  # noqa: E402
from gcs_planner.aircraft.profile import VehicleProfile  # noqa: E402
from gcs_planner.cli import main  # noqa: E402
from gcs_planner.dryrun.run import EXIT_LOST  # noqa: E402
from gcs_planner.scenario.georef import DEFAULT_ORIGIN, LocalFrame  # noqa: E402

COAST = MISSIONS / "coast" / "scenario.toml"


def _low_coast(tmp_path):
    """missions/coast at a quarter of its altitudes (51-842 m), its [vehicle] as stated."""
    return coast_copy(tmp_path, scale=0.25)


def test_the_aerosonde_flies_the_coastal_mission_planned_within_its_climb(tmp_path, capsys):
    """missions/coast's 15 deg climbs are beyond the aerosonde at 25 m/s EAS (its motor): at a
    quarter of its altitudes the dry run plans within the airframe's climb at the top and flies
    it with no loss; at its full height no route is within it (exit 3, before any flight)."""
    path = _low_coast(tmp_path)
    best = airframe_trims("aerosonde", 841.52, 25.0).climb_deg
    assert best < 15.0
    rc = main(["dry-run", str(path), "--flight-model", "jsbsim", "--aircraft", "aerosonde",
               "--json"])  # fmt: skip
    out, err = capsys.readouterr()
    assert rc == 0, err
    assert f"max_climb_angle 15 -> {best:.2f} (the aerosonde's)" in err
    d = json.loads(out)
    assert d["verified"] is True and d["arrived"] is True and d["ok"] is True
    assert d["flight_model"].startswith("JSBSim aerosonde")
    assert d["airframe_limits"] == [] and d["flight_losses"] == 0
    assert d["corrections_as_planned"] is True
    assert len(d["rows"]) == len(d["route"]) - 2
    assert all(r["miss"] <= d["capture_radius"] for r in d["rows"])
    assert d["max_overrun"] is not None and d["max_overrun"] <= d["reserve"]
    top = airframe_trims("aerosonde", 3366.07, 25.0).climb_deg
    rc = main(["dry-run", str(COAST), "--flight-model", "jsbsim", "--aircraft", "aerosonde"])
    out, err = capsys.readouterr()
    assert rc == 3 and f"max_climb_angle 15 -> {top:.2f}" in err and "no feasible route" in err


def test_leg_limits_name_the_leg_and_the_aerosonde_s_ceiling_and_climb():
    model = FlightModel("aerosonde")
    out = model.limits(
        [LegNeed(5, 3000.0, 20.0, 0.0), LegNeed(6, 19000.0, 0.0, 0.0),
         LegNeed(7, 1000.0, 5.0, 40.0)], 25.0,
    )  # fmt: skip
    # item 7 (1 km, 5 deg up, 40 deg of bank) is within the airframe
    assert len(out) == 2
    assert out[0].startswith("leg to item 5 (up to 3,000 m): climbs 20.0 deg")
    assert "the aerosonde at full throttle climbs at most" in out[0]
    assert out[1] == (
        "leg to item 6 (up to 19,000 m): the aerosonde cannot fly level at 25 m/s EAS at "
        "19,000 m (no trim: beyond its ceiling or speed range there)"
    )


def test_a_leg_beyond_the_airframe_is_refused_before_the_flight_starts():
    """The start trims (1 km), the second leg climbs to 19 km: nothing is flown."""
    frame = LocalFrame(DEFAULT_ORIGIN)
    profile = VehicleProfile(turn_radius=300.0, cruise_airspeed=25.0)
    cmds = [NavCommand(1, 16, (3000.0, 0.0, 1000.0), (0.0, 1.0, 0.0, 0.0)),
            NavCommand(2, 16, (60000.0, 0.0, 19000.0), (0.0, 1.0, 0.0, 0.0))]  # fmt: skip
    flight = guidance.fly([], frame, (0.0, 0.0, 1000.0), profile, commands=cmds,
                          flight_model=FlightModel("aerosonde"))  # fmt: skip
    assert flight.ended == guidance.NOT_FLOWN
    assert len(flight.t) == 1 and flight.xyz[0].tolist() == [0.0, 0.0, 1000.0]
    assert any(
        text.startswith("leg to item 2 (up to 19,000 m): the aerosonde cannot fly level")
        for text in flight.limits
    )


def _coast(tmp_path, cruise: float):
    """missions/coast flown at ``cruise`` m/s."""
    text = COAST.read_text().replace("cruise_airspeed = 25 ", f"cruise_airspeed = {cruise:g} ")
    assert f"cruise_airspeed = {cruise:g} " in text
    (tmp_path / "scenario.toml").write_text(text)
    (tmp_path / "landmarks.csv").write_text((COAST.parent / "landmarks.csv").read_text())
    return tmp_path / "scenario.toml"


@pytest.mark.parametrize(
    ("cruise", "aircraft", "says"),
    [
        # below the aerosonde's stall (13.8 m/s EAS: tests/aircraft/test_aerosonde.py holds it
        # to the wing's greatest lift at the airframe's weight)
        (12.0, "aerosonde", "the aerosonde cannot fly level at 12 m/s EAS at 1,500 m"),
        (25.0, "c172r", "the c172r cannot fly level at 25 m/s EAS at 1,500 m"),
    ],
)
def test_the_report_of_a_flight_that_never_started_lists_no_misses(
    tmp_path, capsys, cruise, aircraft, says
):
    path = _coast(tmp_path, cruise)
    flags = ["--flight-model", "jsbsim", "--aircraft", aircraft, "--runs", "3"]
    rc = main(["dry-run", str(path), *flags])
    out, err = capsys.readouterr()
    assert rc == EXIT_LOST
    assert says in out and "CANNOT FLY: leg to item" in out
    assert "flight: NOT FLOWN" in out
    assert "corrections: none: the flight never started" in out
    assert "runs: none of the 3 flown" in out
    assert "result: the mission cannot be flown" in out
    for never in ("MISSED", "missed:", "before the vehicle was lost", "lost by the flight"):
        assert never not in out
    rc = main(["dry-run", str(path), *flags, "--json"])
    d = json.loads(capsys.readouterr()[0])
    assert rc == EXIT_LOST and d["ok"] is False
    assert d["rows"] == [] and d["lost_runs"] == [] and d["flight_losses"] == 0
    assert any(says in limit for limit in d["airframe_limits"])
