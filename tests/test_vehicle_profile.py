"""The vehicle profile: where the aircraft's envelope comes from (TOML `[vehicle]`, flags,
airspeed and bank), what the plan says of it, and bad values named by file, row and field."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from test_readers import _toml_with, expect_error

from gcs_planner.errors import InputError
from gcs_planner.scenario.readers import load_scenario
from gcs_planner.vehicle import G, VehicleProfile, bank_angle_for, turn_radius_from


def with_vehicle(tmp_path: Path, body: str) -> Path:
    path = _toml_with(tmp_path)
    path.write_text(path.read_text() + "[vehicle]\n" + body)
    return path


def test_vehicle_table_sets_the_envelope(tmp_path: Path) -> None:
    path = with_vehicle(
        tmp_path,
        "turn_radius = 250\nmax_climb_angle = 12\nmax_descent_angle = 14\n"
        'cruise_airspeed = 30\nleg_model = "cs3d"\n',
    )
    v = load_scenario(path, {}).vehicle
    assert (v.turn_radius, v.max_climb_angle, v.max_descent_angle) == (250, 12, 14)
    assert (v.cruise_airspeed, v.leg_model, v.radius_source) == (30, "cs3d", "turn_radius")
    assert v.climb_rate == pytest.approx(30 * math.sin(math.radians(12)))


def test_airspeed_and_bank_give_the_turning_radius(tmp_path: Path) -> None:
    path = with_vehicle(tmp_path, "cruise_airspeed = 25\nmax_bank_angle = 30\n")
    v = load_scenario(path, {}).vehicle
    assert v.turn_radius == pytest.approx(25**2 / (G * math.tan(math.radians(30))))
    assert v.radius_source == "airspeed and bank"
    assert "from 25 m/s at 30.0 deg bank" in v.describe()
    # a radius on the command line wins over the file's bank, and says so
    over = load_scenario(path, {"turn_radius": 180.0}).vehicle
    assert over.turn_radius == 180.0 and over.radius_source == "turn_radius"


def test_radius_and_bank_together_in_a_file_are_refused(tmp_path: Path) -> None:
    path = with_vehicle(tmp_path, "turn_radius = 200\ncruise_airspeed = 25\nmax_bank_angle = 30\n")
    err = expect_error(path, {}, field="max_bank_angle")
    assert "either turn_radius" in str(err)


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ("max_climb_angle = 0\n", "max_climb_angle"),
        ("max_descent_angle = 95\n", "max_descent_angle"),
        ('leg_model = "dubins"\n', "leg_model"),
        ("max_bank_angle = 75\n", "max_bank_angle"),
        ("cruise_airspeed = -3\n", "cruise_airspeed"),
        ('cruise_airspeed = "fast"\n', "vehicle.cruise_airspeed"),
        ("wingspan = 3\n", "vehicle.wingspan"),
        ("reserve = -1\n", "reserve"),
    ],
)
def test_bad_vehicle_values_name_file_row_and_field(tmp_path: Path, body: str, field: str) -> None:
    path = with_vehicle(tmp_path, body)
    err = expect_error(path, {}, field=field)
    assert err.row is not None


def test_a_value_given_twice_is_refused(tmp_path: Path) -> None:
    path = _toml_with(tmp_path, parameters="turn_radius = 150\n")
    path.write_text(path.read_text() + "[vehicle]\nturn_radius = 200\n")
    with pytest.raises(InputError, match="given twice"):
        load_scenario(path, {})


def test_the_flight_reserve_stands_in_the_vehicle_table_and_reaches_the_plan(
    tmp_path: Path,
) -> None:
    """How far the autopilot strays from the plan is the aircraft's: `[vehicle] reserve`;
    the plan JSON carries it with the parameters, and --reserve on the command line wins."""
    path = with_vehicle(tmp_path, "reserve = 120\n")
    assert load_scenario(path, {}).params.reserve == 120
    assert load_scenario(path, {"reserve": 0.0}).params.reserve == 0
    out = subprocess.run(
        [sys.executable, "-m", "gcs_planner", "plan", str(path), "--json", "--reserve", "75"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["parameters"]["reserve"] == 75
    bad = subprocess.run(
        [sys.executable, "-m", "gcs_planner", "plan", str(path), "--reserve", "1e9"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    assert "reserve" in bad.stderr and "command line" in bad.stderr


def test_radius_and_bank_are_inverse() -> None:
    for v, phi in ((20.0, 15.0), (25.0, 30.0), (40.0, 45.0)):
        assert bank_angle_for(v, turn_radius_from(v, phi)) == pytest.approx(phi)
    assert VehicleProfile(turn_radius=0).turn_rate == math.inf


def test_flags_reach_the_plan_and_bad_flags_exit_2(tmp_path: Path) -> None:
    path = _toml_with(tmp_path)
    base = [sys.executable, "-m", "gcs_planner", "plan", str(path), "--json"]
    ok = subprocess.run(
        [*base, "--cruise-airspeed", "22", "--max-bank-angle", "35", "--max-climb-angle", "12"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert ok.returncode == 0, ok.stderr
    vehicle = json.loads(ok.stdout)["vehicle"]
    assert vehicle["radius_source"] == "airspeed and bank"
    assert vehicle["bank_angle_deg"] == pytest.approx(35.0)
    bad = subprocess.run(
        [*base, "--leg-model", "helicopter"], capture_output=True, text=True, timeout=300
    )
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
    bad = subprocess.run(
        [*base, "--max-bank-angle", "nan"], capture_output=True, text=True, timeout=300
    )
    assert bad.returncode == 2 and "Traceback" not in bad.stderr
