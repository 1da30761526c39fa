"""The fix report of a policy switched on board: what the correction sensor (or its companion
computer) writes to the autopilot for the applet to read (docs/flying-policies.md, "Switching
on board"). Both ends share it: the applet's generator (mission/onboard_applet.py) and the mock
vehicle's sensor (sim/onboard_flight.py), which must not import the planner; so this module
imports nothing of it.

The report is the parameter ``PLCY_FIX`` (the applet adds it: ``param:add_table`` with
``PARAM_TABLE_KEY`` and ``PARAM_PREFIX``), written with PARAM_SET to ``10 * code + outcome``:
``code`` is the landmark's row in the scenario's point list, from 1, and ``outcome`` one of
:data:`OUTCOMES`.
"""

from __future__ import annotations

from collections.abc import Sequence

APPLET_FILE = "policy.lua"
PARAM_TABLE_KEY = 48  # any key 0..200 no other script on the vehicle uses (param:add_table)
PARAM_PREFIX = "PLCY_"
REPORT_PARAM = PARAM_PREFIX + "FIX"
OUTCOMES = {"made": 1, "FAILED": 2, "MISSED": 3}


def point_codes(ids: Sequence[str]) -> dict[str, int]:
    """Each landmark's report code, from the scenario's point ids in order: its row, from 1."""
    return {str(pid): k + 1 for k, pid in enumerate(ids)}


def report_value(code: int, outcome: str) -> float:
    """The value the correction sensor writes to ``PLCY_FIX`` for one fix."""
    return float(10 * code + OUTCOMES[outcome])
