"""The endurance a dry run judges each flight against: ``--endurance MINUTES``, else the scenario
TOML's ``[vehicle] endurance`` (the minutes of flight the aircraft's battery or fuel gives),
else none.

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


def vehicle_endurance(text: str | None, scenario: str | Path | None) -> float | None:
    """The endurance (minutes) of the flag's ``text``, else of the scenario file's
    ``[vehicle] endurance``; None when neither gives one. A bad value is an InputError naming
    the flag (the file's own are checked when it is read)."""
    if text is not None:
        return _minutes(text)
    if scenario is None or Path(scenario).suffix.lower() != ".toml":
        return None
    terms = read_scenario_toml(Path(scenario)).autopilot_terms
    if KEY not in terms:
        return None
    value, _ = terms[KEY]
    return float(value)  # type: ignore[arg-type]


def _minutes(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"not a number of minutes: {text!r}", field=FLAG) from None
    if not (math.isfinite(value) and 0.0 < value <= LONGEST_MIN):
        raise InputError(f"must be minutes in (0, {LONGEST_MIN:g}], got {text!r}", field=FLAG)
    return value
