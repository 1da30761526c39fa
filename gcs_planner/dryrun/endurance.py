"""The endurance a dry run judges each flight against and the plan keeps to: ``--endurance
MINUTES``, else the scenario TOML's ``[vehicle] endurance`` (the minutes of flight the
aircraft's battery or fuel gives), else its battery's energy over the power at cruise less a
reserve (``battery_wh``, ``cruise_power_w``, ``battery_reserve``), else none.

Past its endurance the aircraft cannot fly on: its low-battery failsafe acts (ArduPlane
BATT_FS_LOW_ACT, ``libraries/AP_BattMonitor/AP_BattMonitor_Params.cpp``: return, land or
terminate; PX4 COM_LOW_BAT_ACT, ``src/modules/commander/commander_params.c``: return or land),
or, left at the shipped warning only, the battery runs out. Either way the mission ends there:
a flight that has not come to B by then is lost, and lost by the flight (sim/guidance.py
``fly``'s ``endurance``; the time is counted from A, where the dry run's flight starts).
"""

from __future__ import annotations

import math
from pathlib import Path

from gcs_planner.errors import InputError
from gcs_planner.scenario.toml_reader import read_scenario_toml

FLAG = "--endurance"
KEY = "endurance"
# A week of flight: beyond any aircraft's, and a flight's time limit stays finite.
LONGEST_MIN = 7 * 24 * 60.0


# The battery's energy kept in reserve when ``[vehicle] battery_reserve`` is not given: PX4's
# low-battery threshold BAT_LOW_THR, 15 % (src/lib/battery/module.yaml; ArduPlane's
# BATT_LOW_MAH / BATT_LOW_VOLT are off by default, so it is the stated figure for both).
DEFAULT_BATTERY_RESERVE = 0.15
BATTERY_KEYS = ("battery_wh", "cruise_power_w")


def vehicle_endurance(text: str | None, scenario: str | Path | None) -> float | None:
    """The endurance (minutes) of the flag's ``text``, else of the scenario file's
    ``[vehicle] endurance``, else of its battery: ``battery_wh`` (1 - ``battery_reserve``)
    / ``cruise_power_w``; None when none gives one. A bad value is an InputError naming the
    flag, or the file and key (the file's own are checked when it is read)."""
    if text is not None:
        return _minutes(text)
    if scenario is None or Path(scenario).suffix.lower() != ".toml":
        return None
    terms = read_scenario_toml(Path(scenario)).autopilot_terms
    if KEY in terms:
        value, _ = terms[KEY]
        return float(value)  # type: ignore[arg-type]
    given = [k for k in BATTERY_KEYS if k in terms]
    if not given:
        return None
    if len(given) < len(BATTERY_KEYS):
        missing = next(k for k in BATTERY_KEYS if k not in terms)
        _, line = terms[given[0]]
        raise InputError(
            f"needs {missing} too (the endurance is the battery's energy over the power at cruise)",
            file=str(scenario),
            row=line,
            field=f"vehicle.{missing}",
        )
    energy = float(terms["battery_wh"][0])  # type: ignore[arg-type]
    power = float(terms["cruise_power_w"][0])  # type: ignore[arg-type]
    kept = terms.get("battery_reserve")
    reserve = DEFAULT_BATTERY_RESERVE if kept is None else float(kept[0])  # type: ignore[arg-type]
    return min(energy * (1.0 - reserve) / power * 60.0, LONGEST_MIN)


def _minutes(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"not a number of minutes: {text!r}", field=FLAG) from None
    if not (math.isfinite(value) and 0.0 < value <= LONGEST_MIN):
        raise InputError(f"must be minutes in (0, {LONGEST_MIN:g}], got {text!r}", field=FLAG)
    return value
