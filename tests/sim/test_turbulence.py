"""Vertical turbulence (sim/turbulence.py, sim/wind.py): the Dryden vertical component of
MIL-F-8785C, its scale length and the standard's intensities at altitude, one exact seeded step
of it, the aircraft moving with the air, and the dry run flying it (``--turbulence``, the
scenario's ``[environment] turbulence``)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from gcs_planner.sim.aircraft import AircraftState, Envelope, step
from gcs_planner.sim.turbulence import (
    FT,
    KNOT,
    Turbulence,
    dryden_step,
    parse_turbulence,
    scale_length_w,
)
from gcs_planner.sim.wind import WindField, WindModel, WindSpec
from support.short_line import short_line

from gcs_planner.cli import main
from gcs_planner.dryrun.air import flown_turbulence
from gcs_planner.errors import InputError

STATIONARY = np.array([[0.5, 0.25], [0.25, 0.25]])


@pytest.mark.parametrize("du", [1e-4, 0.02, 0.5, 3.0])
def test_one_step_keeps_the_stationary_covariance_and_the_output_variance_is_one(du):
    """The step's transition and its noise (drawn through unit normals) map the stationary
    covariance onto itself, whatever the step; sqrt(3) x1 + (1 - sqrt(3)) x2 has variance 1."""
    e = math.exp(-du)
    phi = e * np.array([[1.0, 0.0], [du, 1.0]])
    # The step is linear: its noise's covariance from the unit draws' columns.
    origin = np.array(dryden_step(0.0, 0.0, du, 0.0, 0.0))
    cols = [np.array(dryden_step(0.0, 0.0, du, *n)) - origin for n in ((1.0, 0.0), (0.0, 1.0))]
    noise = np.column_stack(cols)
    got = phi @ STATIONARY @ phi.T + noise @ noise.T
    assert got == pytest.approx(STATIONARY, rel=1e-6, abs=1e-12)
    c = np.array([math.sqrt(3.0), 1.0 - math.sqrt(3.0)])
    assert c @ STATIONARY @ c == pytest.approx(1.0)


def test_scale_length_is_the_standards_at_low_medium_and_high_altitude():
    """MIL-F-8785C: L_w = h below 1,000 ft (10 ft at least), 1,750 ft above 2,000 ft, linear
    between."""
    assert scale_length_w(500 * FT) == pytest.approx(500 * FT)
    assert scale_length_w(0.0) == pytest.approx(10 * FT)
    assert scale_length_w(1500 * FT) == pytest.approx(1375 * FT)
    assert scale_length_w(5000.0) == pytest.approx(1750 * FT)


def test_the_levels_are_the_standards_intensities():
    """Low altitude: sigma_w = 0.1 W20 (15, 30, 45 kt); from 2,000 ft the curves of Fig. 7
    (light 7.4 ft/s at 3,750 ft, moderate 10.6, severe 23.0); a number is flown everywhere."""
    for level, w20, at_3750 in (("light", 15, 7.4), ("moderate", 30, 10.6), ("severe", 45, 23.0)):
        t = parse_turbulence(level)
        assert t.sigma_at(100.0) == pytest.approx(0.1 * w20 * KNOT)
        assert t.sigma_at(3750 * FT) == pytest.approx(at_3750 * FT)
        lo, hi = t.sigma_at(1000 * FT), t.sigma_at(2000 * FT)
        assert t.sigma_at(1500 * FT) == pytest.approx(0.5 * (lo + hi))
    assert parse_turbulence("0.5").sigma_at(9000.0) == 0.5
    assert not parse_turbulence("0").present
    for bad in ("gale", "-1", "nan", "25"):
        with pytest.raises(ValueError):
            parse_turbulence(bad)


def test_the_vertical_gusts_are_seeded_of_the_stated_deviation_and_drydens_correlation():
    """Flown at 25 m/s at 100 m (L_w = 100 m): the draws repeat by seed, their deviation is
    sigma_w and the correlation one second apart is Dryden's (1 - x / 2L) exp(-x / L) at
    x = 25 m; the horizontal gusts of a seed are the same with or without turbulence."""
    model = WindModel(0.0, 0.0, 1.0, seed=11, turbulence=Turbulence(1.5))
    a, b = WindField(model, 25.0), WindField(model, 25.0)
    w = np.array([a.air(1.0, 100.0, 25.0) for _ in range(20000)])
    assert np.array_equal(w[:50], np.array([b.air(1.0, 100.0, 25.0) for _ in range(50)]))
    assert w[:, 2].std() == pytest.approx(1.5, rel=0.08)
    lag = np.corrcoef(w[:-1, 2], w[1:, 2])[0, 1]
    x = 25.0 / 100.0
    assert lag == pytest.approx((1 - x / 2) * math.exp(-x), abs=0.02)
    plain = WindField(WindModel(0.0, 0.0, 1.0, seed=11), 25.0)
    assert np.array_equal(w[:100, :2], np.array([plain.step(1.0) for _ in range(100)]))


def test_the_aircraft_rises_and_sinks_with_the_air():
    """A vertical wind moves the aircraft with it: its height and its climb over the sea are
    the autopilot's climb plus the air's."""
    s = AircraftState(0.0, 0.0, 1000.0, 0.0)
    env = Envelope(25.0, 45.0, 5.0, 5.0)
    up = step(s, env, 0.0, 1.0, 2.0, (0.0, 0.0, 1.5))
    assert up.z == pytest.approx(1000.0 + 2.0 * 2.5) and up.climb_rate == pytest.approx(2.5)
    assert step(s, env, 0.0, 1.0, 2.0, (0.0, 0.0)).z == pytest.approx(1002.0)


def test_turbulence_is_not_still_air_and_says_what_it_is():
    spec = WindSpec(turbulence=Turbulence(level="light"))
    assert not spec.still and "light vertical turbulence" in spec.describe()
    drawn = spec.draw(np.random.default_rng(1))
    assert drawn.turbulent and not drawn.still
    assert WindSpec(turbulence=Turbulence(0.0)).still


def test_the_flag_wins_over_the_scenarios_environment(tmp_path):
    path = short_line(tmp_path, '\n[environment]\nturbulence = "moderate"\n')
    assert flown_turbulence(None, path) == Turbulence(level="moderate")
    assert flown_turbulence("0.7", path) == Turbulence(0.7)
    assert flown_turbulence("0", path) is None
    assert flown_turbulence(None, short_line(tmp_path, "")) is None
    with pytest.raises(InputError) as err:
        flown_turbulence("stormy", path)
    assert err.value.field == "--turbulence"


def test_a_bad_environment_turbulence_is_exit_2_naming_the_file_and_key(tmp_path, capsys):
    path = short_line(tmp_path, "\n[environment]\nturbulence = -2\n")
    assert main(["dry-run", str(path), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "environment.turbulence" in err and "line.toml" in err


def test_the_dry_run_flies_the_scenarios_turbulence(tmp_path, capsys):
    """The short line at 5,000 m in the scenario's light turbulence (2.1 m/s there), flown by a
    plan made for still air (``--design-turbulence 0``): the report names it, and the flight's
    height wanders with the air."""
    path = short_line(tmp_path, '\n[environment]\nturbulence = "light"\n')
    rc = main(["dry-run", str(path), "--design-turbulence", "0", "--json", "--quiet"])
    d = json.loads(capsys.readouterr().out)
    assert rc in (0, 5) and d["verified"]
    assert "light vertical turbulence" in d["wind"]
    rc = main(["dry-run", str(path), "--turbulence", "0", "--json", "--quiet"])
    d = json.loads(capsys.readouterr().out)
    assert rc == 0 and d["wind"] == "still air"


def test_jsbsim_rises_with_the_air():
    """The vertical air reaches the JSBSim airframe as its wind down: in 3 m/s of rising air
    the c172r is carried up while its loops fly it back; in still air it holds its height."""
    import jsbsim  # noqa: F401 - the test extra installs it: a missing one fails, never skips
    from gcs_planner.sim.jsbsim_airframe import JSBSimAirframe

    env = Envelope(45.0, 30.0, 5.0, 5.0)
    heights = {}
    for wz in (0.0, 3.0):
        airframe = JSBSimAirframe("c172r", AircraftState(0.0, 0.0, 1000.0, 0.0), 45.0, 0.0)
        s = airframe.state()
        for _ in range(6):
            s = airframe.step(s, env, 0.0, 0.0, 0.5, (0.0, 0.0, wz))
        heights[wz] = s.z
    assert heights[0.0] == pytest.approx(1000.0, abs=0.5)
    assert heights[3.0] > 1002.0
