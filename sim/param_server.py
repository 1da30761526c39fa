"""The vehicle's parameter server: PARAM_REQUEST_LIST / _READ / PARAM_SET answered with
PARAM_VALUE, as ArduPilot and PX4 answer them.

It serves the parameters the ground station reads and sets (the loiter radius and the flight
envelope of :mod:`gcs_planner.vehicle`, under each autopilot's own names). A write is checked
before it is stored: a value that is not finite, or does not fit the parameter's integer type,
leaves the parameter as it was, and the PARAM_VALUE sent back says so. Unknown names get no
answer, as on both autopilots.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any

from gcs_planner.link.connection import mavlink
from gcs_planner.vehicle import (
    DEFAULT_CRUISE_AIRSPEED,
    ENVELOPE_PARAMS,
    LOITER_RADIUS_PARAM,
    PARAM_TYPE_INT16,
    PARAM_TYPE_REAL32,
    VehicleProfile,
)

INT_RANGES = {
    mavlink.MAV_PARAM_TYPE_INT8: (-(2**7), 2**7 - 1),
    mavlink.MAV_PARAM_TYPE_UINT8: (0, 2**8 - 1),
    mavlink.MAV_PARAM_TYPE_INT16: (-(2**15), 2**15 - 1),
    mavlink.MAV_PARAM_TYPE_UINT16: (0, 2**16 - 1),
    mavlink.MAV_PARAM_TYPE_INT32: (-(2**31), 2**31 - 1),
    mavlink.MAV_PARAM_TYPE_UINT32: (0, 2**32 - 1),
}
# What the autopilots ship with where the aircraft does not say (ArduPlane ROLL_LIMIT_DEG 45,
# TECS_CLMB_MAX 5, TECS_SINK_MAX 5, WP_RADIUS 90; PX4 FW_R_LIM 50, FW_T_CLMB_MAX 5,
# FW_T_SINK_MAX 5, NAV_ACC_RAD 10).
SHIPPED = {
    "ardupilot": {"bank_limit": 45.0, "climb_rate": 5.0, "sink_rate": 5.0, "acceptance_radius": 90},
    "px4": {"bank_limit": 50.0, "climb_rate": 5.0, "sink_rate": 5.0, "acceptance_radius": 10.0},
}
# ArduPlane's WP_RADIUS is an int16 like WP_LOITER_RAD; every other one here is a float.
_INT_PARAMS = {"WP_RADIUS", "WP_LOITER_RAD"}


def parameter_table(
    flavour: str, profile: VehicleProfile | None = None
) -> dict[str, tuple[float, int]]:
    """name -> (value, MAV_PARAM_TYPE) for ``flavour``, from ``profile`` where it says."""
    shipped = SHIPPED[flavour]
    cruise = profile.cruise_airspeed if profile is not None else DEFAULT_CRUISE_AIRSPEED
    radius = profile.turn_radius if profile is not None and profile.turn_radius > 0 else 80.0
    bank = shipped["bank_limit"]
    climb, sink = shipped["climb_rate"], shipped["sink_rate"]
    if profile is not None:
        if profile.turn_radius > 0:
            bank = round(profile.bank_angle, 1)
        if math.isfinite(profile.climb_rate):
            climb = round(profile.climb_rate, 2)
        if math.isfinite(profile.sink_rate):
            sink = round(profile.sink_rate, 2)
    values = {
        "cruise_airspeed": cruise,
        "bank_limit": bank,
        "climb_rate": climb,
        "sink_rate": sink,
        "acceptance_radius": shipped["acceptance_radius"],
    }
    table: dict[str, tuple[float, int]] = {}
    loiter_name, loiter_type = LOITER_RADIUS_PARAM[flavour]
    loiter = float(round(radius)) if loiter_type == PARAM_TYPE_INT16 else float(radius)
    table[loiter_name] = (loiter, loiter_type)
    for word, name in ENVELOPE_PARAMS[flavour].items():
        ptype = PARAM_TYPE_INT16 if name in _INT_PARAMS else PARAM_TYPE_REAL32
        value = float(values[word])
        table[name] = (float(round(value)) if ptype == PARAM_TYPE_INT16 else value, ptype)
    return table


def param_name(pid: Any) -> str:
    if isinstance(pid, bytes):
        pid = pid.decode("ascii", "replace")
    return str(pid).split("\x00", 1)[0]


def accepted_value(value: float, ptype: int) -> float | None:
    """The value a PARAM_SET stores for a parameter of ``ptype``, or None when it is refused."""
    if not math.isfinite(value):
        return None
    if ptype in INT_RANGES:
        lo, hi = INT_RANGES[ptype]
        value = float(round(value))
        if not lo <= value <= hi:
            return None
    elif abs(value) > 3.4028234663852886e38:
        return None
    return value


class ParamServer:
    """The parameters of one vehicle; ``lock`` guards them."""

    HANDLED = ("PARAM_SET", "PARAM_REQUEST_READ", "PARAM_REQUEST_LIST")

    def __init__(
        self,
        mav: Any,
        send: Callable[[Any], None],
        table: dict[str, tuple[float, int]],
        lock: threading.Lock,
    ) -> None:
        self.mav = mav
        self.send = send
        self.table = dict(table)
        self.lock = lock
        self.refused = 0  # writes refused (not finite, out of the type's range)

    @property
    def values(self) -> dict[str, float]:
        with self.lock:
            return {k: v for k, (v, _) in self.table.items()}

    def send_value(self, name: str) -> None:
        with self.lock:
            names = list(self.table)
            value, ptype = self.table[name]
        self.send(
            self.mav.param_value_encode(
                name.encode("ascii"), value, ptype, len(names), names.index(name)
            )
        )

    def handle(self, msg: Any, peer: tuple[int, int]) -> None:
        kind = msg.get_type()
        if kind == "PARAM_SET":
            self.on_set(msg)
        elif kind == "PARAM_REQUEST_READ":
            self.on_read(msg)
        elif kind == "PARAM_REQUEST_LIST":
            for name in list(self.values):
                self.send_value(name)

    def on_set(self, msg: Any) -> None:
        name = param_name(msg.param_id)
        with self.lock:
            if name not in self.table:
                return  # autopilots stay silent about parameters they do not have
            _, ptype = self.table[name]
            value = accepted_value(float(msg.param_value), ptype)
            if value is None:
                self.refused += 1
            else:
                self.table[name] = (value, ptype)
        self.send_value(name)  # what it holds now: the ground station sees a refusal

    def on_read(self, msg: Any) -> None:
        name = param_name(msg.param_id)
        with self.lock:
            names = list(self.table)
        index = int(msg.param_index)
        if index >= 0:
            if index >= len(names):
                return
            name = names[index]
        if name in names:
            self.send_value(name)
