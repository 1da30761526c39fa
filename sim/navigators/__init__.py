"""One navigator per autopilot, sharing one base (sim/navigators/base.py): ArduPlane
(arduplane.py) and PX4 (px4.py), with the parameters they read (params.py)."""

from __future__ import annotations

from sim.navigators.arduplane import ArduPlaneNavigator
from sim.navigators.base import Navigator
from sim.navigators.params import AutopilotParams
from sim.navigators.px4 import PX4Navigator

NAVIGATORS: dict[str, type[Navigator]] = {"ardupilot": ArduPlaneNavigator, "px4": PX4Navigator}

__all__ = ["NAVIGATORS", "ArduPlaneNavigator", "AutopilotParams", "Navigator", "PX4Navigator"]
