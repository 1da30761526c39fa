"""sim/ is the aircraft's side: it may read the vehicle profile, the landmark database and the
MAVLink item types, never the planner (its answers would leak into the check of them)."""

from __future__ import annotations

import functools
import json
import subprocess
import sys

import pytest

PLANNER = ("gcs_planner.core", "gcs_planner.geometry", "gcs_planner.mission.builder")
CLIENT = ("gcs_planner.link",)


# Memoised: both tests ask about the same modules, and a fresh interpreter's answer for one
# module does not change within a session.
@functools.cache
def imported_by(module: str) -> tuple[str, ...]:
    """The modules loaded by importing ``module`` alone, in a fresh interpreter."""
    code = f"import json, sys, {module}; print(json.dumps(sorted(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    ).stdout
    return tuple(json.loads(out))


@pytest.mark.parametrize(
    "module",
    [
        "gcs_planner.sim.aircraft",
        "gcs_planner.sim.guidance",
        "gcs_planner.sim.replay",
        "gcs_planner.sim.telemetry",
        "gcs_planner.sim.vehicle",
        "gcs_planner.sim.ins",
        "gcs_planner.sim.wind",
        "gcs_planner.sim.atmosphere",
        "gcs_planner.sim.navigators",
        "gcs_planner.sim.scripting",
        "gcs_planner.sim.onboard_flight",
    ],  # fmt: skip
)
def test_sim_does_not_import_the_planning_core(module):
    loaded = imported_by(module)
    assert module in loaded
    assert not [m for m in loaded if m.startswith(PLANNER)]


@pytest.mark.parametrize(
    "module",
    [
        "gcs_planner.sim.aircraft",
        "gcs_planner.sim.guidance",
        "gcs_planner.sim.replay",
        "gcs_planner.sim.telemetry",
        "gcs_planner.sim.ins",
        "gcs_planner.sim.wind",
    ],
)
def test_the_flight_does_not_import_the_ground_stations_client(module):
    loaded = imported_by(module)
    assert not [m for m in loaded if m.startswith(CLIENT)]
