"""The endurance from the battery (gcs_planner/dryrun/endurance.py): ``[vehicle] battery_wh``
over ``cruise_power_w``, less ``battery_reserve`` (default PX4's BAT_LOW_THR, 15 %), when no
endurance is stated; the stated endurance and the flag win, and the planner keeps to it."""

from __future__ import annotations

import pytest
from support.short_line import short_line

from gcs_planner.cli import main
from gcs_planner.dryrun.endurance import DEFAULT_BATTERY_RESERVE, vehicle_endurance


def test_the_battery_gives_the_endurance_less_its_reserve(tmp_path):
    path = short_line(tmp_path, "\n[vehicle]\nbattery_wh = 100\ncruise_power_w = 50\n")
    assert vehicle_endurance(None, path) == pytest.approx(120.0 * (1 - DEFAULT_BATTERY_RESERVE))
    path = short_line(
        tmp_path, "\n[vehicle]\nbattery_wh = 100\ncruise_power_w = 50\nbattery_reserve = 0.25\n"
    )
    assert vehicle_endurance(None, path) == pytest.approx(90.0)
    assert vehicle_endurance("30", path) == 30.0
    path = short_line(
        tmp_path, "\n[vehicle]\nendurance = 45\nbattery_wh = 100\ncruise_power_w = 50\n"
    )
    assert vehicle_endurance(None, path) == 45.0


@pytest.mark.parametrize(
    ("table", "field"),
    [
        ("battery_wh = 100\n", "vehicle.cruise_power_w"),
        ("battery_wh = 100\ncruise_power_w = 0\n", "vehicle.cruise_power_w"),
        ("battery_wh = 100\ncruise_power_w = 50\nbattery_reserve = 1\n", "vehicle.battery_reserve"),
    ],
    ids=["no power", "no power at all", "all in reserve"],
)
def test_a_bad_battery_is_exit_2_naming_the_file_and_key(tmp_path, capsys, table, field):
    path = short_line(tmp_path, "\n[vehicle]\n" + table)
    assert main(["plan", str(path)]) == 2
    err = capsys.readouterr().err
    assert field in err and "line.toml" in err and "Traceback" not in err


def test_the_plan_keeps_to_the_batterys_endurance(tmp_path, capsys):
    """The 24 km line at 25 m/s EAS (5,000 m) takes about 12 minutes: 10 Wh at 60 W (8.5
    minutes with the reserve) cannot fly it, 20 Wh (17 minutes) can."""
    path = short_line(tmp_path, "\n[vehicle]\nbattery_wh = 10\ncruise_power_w = 60\n")
    assert main(["plan", str(path)]) == 3
    assert "endurance of 8.5 min" in capsys.readouterr().err
    path = short_line(tmp_path, "\n[vehicle]\nbattery_wh = 20\ncruise_power_w = 60\n")
    assert main(["plan", str(path)]) == 0
    assert "within the endurance of 17 min" in capsys.readouterr().out
