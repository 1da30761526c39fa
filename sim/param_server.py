"""The vehicle's parameter server: PARAM_REQUEST_LIST / _READ / PARAM_SET answered with
PARAM_VALUE, as ArduPilot and PX4 answer them.

It serves its firmware's parameters as the firmware ships them (the records of
:mod:`gcs_planner.aircraft.autopilot`: ArduPlane TECS_CLMB_MAX 5, ROLL_LIMIT_DEG 45, ...; PX4
FW_T_CLMB_R_SP 3, FW_R_LIM 50, ...), except where the scenario's aircraft says otherwise: its
cruise airspeed, its turning radius as the loiter radius, and its bank limit when the scenario
gives one (``max_bank_angle``). The plan's climb and descent limits are the plan's assumptions,
not the aircraft's, and are never served as its rates.

A write is checked before it is stored: a value the flight cannot use (not finite, outside the
parameter's range, or not fitting its integer type) leaves the parameter as it was, the
PARAM_VALUE sent back says so, and a STATUSTEXT says why. Real autopilots take nearly anything
(ArduPilot's @Range and PX4's @min/@max are ground-station metadata); the mock refuses what its
flight model could not fly, so that a hostile value is a refusal, never a dead flight. Unknown
names get no answer, as on both autopilots.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any

from gcs_planner.aircraft.autopilot import (
    DEFAULT_AUTOPILOT,
    EffectiveParameters,
    autopilot_for,
    effective,
)
from gcs_planner.aircraft.profile import VehicleProfile
from gcs_planner.link.connection import mavlink

INT_RANGES = {
    mavlink.MAV_PARAM_TYPE_INT8: (-(2**7), 2**7 - 1),
    mavlink.MAV_PARAM_TYPE_UINT8: (0, 2**8 - 1),
    mavlink.MAV_PARAM_TYPE_INT16: (-(2**15), 2**15 - 1),
    mavlink.MAV_PARAM_TYPE_UINT16: (0, 2**16 - 1),
    mavlink.MAV_PARAM_TYPE_INT32: (-(2**31), 2**31 - 1),
    mavlink.MAV_PARAM_TYPE_UINT32: (0, 2**32 - 1),
}


def parameter_table(
    flavour: str, profile: VehicleProfile | None = None
) -> dict[str, tuple[float, int]]:
    """name -> (value, MAV_PARAM_TYPE) for ``flavour``: the shipped defaults, with the
    scenario's aircraft (``profile``) where it says: cruise airspeed, turning radius as the
    loiter radius, and the bank limit only when the radius came from airspeed and bank."""
    ap = autopilot_for(flavour)
    table = {p.name: (p.default, p.ptype) for p in ap.params}

    def put(name: str, value: float) -> None:
        spec = ap.spec(name)
        assert spec is not None
        table[name] = (spec.stored(value), spec.ptype)

    if profile is not None:
        put(ap.envelope["cruise_airspeed"], profile.cruise_airspeed)
        # An airframe set up to cruise at its airspeed holds it within its airspeed range
        # (both autopilots bound the cruise by it: see gcs_planner.aircraft.autopilot).
        low_name, high_name = ap.airspeed_range
        put(low_name, min(table[low_name][0], profile.cruise_airspeed))
        put(high_name, max(table[high_name][0], profile.cruise_airspeed))
        if profile.turn_radius > 0:
            put(ap.loiter_radius_param, profile.turn_radius)
        if profile.radius_source != "turn_radius" and profile.turn_radius > 0:
            # The scenario gave max_bank_angle: that is the aircraft's roll limit.
            put(ap.envelope["bank_limit"], round(profile.bank_angle, 1))
    return table


def param_name(pid: Any) -> str:
    if isinstance(pid, bytes):
        pid = pid.decode("ascii", "replace")
    return str(pid).split("\x00", 1)[0]


def accepted_value(value: float, ptype: int) -> float | None:
    """The value a PARAM_SET stores for a parameter of ``ptype``, or None when it is refused
    (the type's own limits; the record's ranges are checked by :class:`ParamServer`)."""
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
    """The parameters of one vehicle; ``lock`` guards them. ``statustext(text, severity)``
    announces a refused write (optional)."""

    HANDLED = ("PARAM_SET", "PARAM_REQUEST_READ", "PARAM_REQUEST_LIST")

    def __init__(
        self,
        mav: Any,
        send: Callable[[Any], None],
        table: dict[str, tuple[float, int]],
        lock: threading.Lock,
        *,
        flavour: str = DEFAULT_AUTOPILOT,
        statustext: Callable[..., None] | None = None,
    ) -> None:
        self.mav = mav
        self.send = send
        self.table = dict(table)
        self.lock = lock
        self.flavour = flavour
        self.autopilot = autopilot_for(flavour)
        self.statustext = statustext
        self.refused = 0  # writes refused (not usable by the flight, out of the type's range)

    @property
    def values(self) -> dict[str, float]:
        with self.lock:
            return {k: v for k, (v, _) in self.table.items()}

    @property
    def effective(self) -> EffectiveParameters:
        """The parameters the flight uses now (:func:`gcs_planner.aircraft.autopilot.effective`)."""
        return effective(self.flavour, self.values)

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
        why = None
        with self.lock:
            if name not in self.table:
                return  # autopilots stay silent about parameters they do not have
            _, ptype = self.table[name]
            raw = float(msg.param_value)
            value = accepted_value(raw, ptype)
            why = self.autopilot.refusal(name, raw)
            if value is None and why is None:
                why = f"{name} {raw:g} does not fit its type"
            if why is None and value is not None:
                self.table[name] = (value, ptype)
            else:
                self.refused += 1
        self.send_value(name)  # what it holds now: the ground station sees a refusal
        if why is not None and self.statustext is not None:
            self.statustext(f"Refused: {why}", mavlink.MAV_SEVERITY_WARNING)

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
