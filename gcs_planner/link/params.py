"""Vehicle parameters over MAVLink: PARAM_SET confirmed by the PARAM_VALUE that answers it.

The loiter radius is the one the planner needs: the vehicle must turn no tighter than the
turning radius the route was planned with, and each firmware names the parameter its own way.
"""

from __future__ import annotations

import math
import time

from gcs_planner.aircraft.autopilot import AUTOPILOTS
from gcs_planner.errors import LinkError
from gcs_planner.link.connection import Link, mavlink
from gcs_planner.link.protocol import DEFAULT_RETRIES, DEFAULT_TIMEOUT_S

_INT_TYPES = {
    mavlink.MAV_PARAM_TYPE_INT8: (-(2**7), 2**7 - 1),
    mavlink.MAV_PARAM_TYPE_INT16: (-(2**15) + 1, 2**15 - 1),
    mavlink.MAV_PARAM_TYPE_INT32: (-(2**31), 2**31 - 1),
    mavlink.MAV_PARAM_TYPE_UINT8: (0, 2**8 - 1),
    mavlink.MAV_PARAM_TYPE_UINT16: (0, 2**16 - 1),
}


def _param_id(msg: object) -> str:
    pid = msg.param_id  # type: ignore[attr-defined]
    if isinstance(pid, bytes):
        pid = pid.decode("ascii", "replace")
    return pid.rstrip("\x00")


def _wait_value(link: Link, target: tuple[int, int], name: str, timeout: float) -> float | None:
    deadline = time.monotonic() + timeout
    while (remaining := deadline - time.monotonic()) > 0:
        msg = link.recv(remaining)
        if msg is None:
            return None
        if msg.get_type() != "PARAM_VALUE" or msg.get_srcSystem() != target[0]:
            continue
        if _param_id(msg) == name:
            return float(msg.param_value)
    return None


def read_parameter(
    link: Link,
    target: tuple[int, int],
    name: str,
    *,
    timeout: float = DEFAULT_TIMEOUT_S,
    retries: int = DEFAULT_RETRIES,
) -> float:
    """The value of parameter ``name`` (PARAM_REQUEST_READ by name)."""
    for _ in range(retries + 1):
        link.send(
            link.mav.param_request_read_encode(target[0], target[1], name.encode("ascii"), -1)
        )
        value = _wait_value(link, target, name, timeout)
        if value is not None:
            return value
    raise LinkError(f"the vehicle did not answer a read of parameter {name}")


def set_parameter(
    link: Link,
    target: tuple[int, int],
    name: str,
    value: float,
    param_type: int = mavlink.MAV_PARAM_TYPE_REAL32,
    *,
    timeout: float = DEFAULT_TIMEOUT_S,
    retries: int = DEFAULT_RETRIES,
) -> float:
    """Set ``name`` to ``value`` and return the value the vehicle confirms.

    Raises :class:`LinkError` if the vehicle never confirms (no such parameter: autopilots stay
    silent) or confirms another value (out of its range).
    """
    if len(name) > 16:
        raise LinkError(f"parameter name {name!r} is longer than MAVLink's 16 characters")
    if not math.isfinite(value):
        raise LinkError(f"parameter {name}: {value!r} is not a finite number")
    expected = float(value)
    if param_type in _INT_TYPES:
        lo, hi = _INT_TYPES[param_type]
        expected = float(round(value))
        if not lo <= expected <= hi:
            raise LinkError(f"parameter {name}: {value!r} does not fit its integer type")
    for _ in range(retries + 1):
        link.send(
            link.mav.param_set_encode(
                target[0], target[1], name.encode("ascii"), expected, param_type
            )
        )
        got = _wait_value(link, target, name, timeout)
        if got is None:
            continue
        if abs(got - expected) <= max(1e-3, 1e-6 * abs(expected)):
            return got
        raise LinkError(f"the vehicle set {name} to {got!r}, not {expected!r}")
    raise LinkError(
        f"the vehicle never confirmed {name} = {expected!r} (does it have that parameter?)"
    )


def set_loiter_radius(
    link: Link,
    target: tuple[int, int],
    radius_m: float,
    firmware: str,
    *,
    timeout: float = DEFAULT_TIMEOUT_S,
    retries: int = DEFAULT_RETRIES,
) -> float:
    """Set the firmware's loiter radius parameter (its name and MAV_PARAM_TYPE from the
    autopilot's record) to ``radius_m`` (metres), confirmed."""
    ap = AUTOPILOTS.get(firmware)
    if ap is None:
        known = " or ".join(AUTOPILOTS)
        raise LinkError(f"unknown firmware {firmware!r}: expected {known}")
    name, ptype = ap.loiter_radius_param, ap.loiter_radius_type
    return set_parameter(link, target, name, radius_m, ptype, timeout=timeout, retries=retries)
