"""One navigator per autopilot, sharing one base (sim/navigators/base.py): ArduPlane
(arduplane.py) and PX4 (px4.py), with the parameters they read (params.py); the navigator as
the compiled flight reads it is compiled.py."""

from __future__ import annotations

from gcs_planner.sim.navigators.arduplane import ArduPlaneNavigator
from gcs_planner.sim.navigators.base import Navigator
from gcs_planner.sim.navigators.params import AutopilotParams
from gcs_planner.sim.navigators.px4 import PX4Navigator

from gcs_planner.aircraft.autopilot import ARDUPLANE, PX4

NAVIGATORS: dict[str, type[Navigator]] = {
    ARDUPLANE.firmware: ArduPlaneNavigator,
    PX4.firmware: PX4Navigator,
}

__all__ = ["NAVIGATORS", "ArduPlaneNavigator", "AutopilotParams", "Navigator", "PX4Navigator"]
