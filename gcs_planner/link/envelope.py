"""The aircraft's flight envelope as its autopilot holds it: cruise airspeed, bank limit, climb
and sink rates read from the parameters each firmware names in
:data:`gcs_planner.vehicle.ENVELOPE_PARAMS`, in the planner's words.

The planner limits flight-path angles, the autopilots rates: at cruise airspeed V a climb rate c
is the angle asin(c / V).
"""

from __future__ import annotations

import math

from gcs_planner.errors import LinkError
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.params import read_parameter
from gcs_planner.vehicle import ENVELOPE_PARAMS, FIRMWARES


def envelope_from_parameters(values: dict[str, float]) -> dict[str, float]:
    """Planner overrides (cruise_airspeed, max_bank_angle, max_climb_angle, max_descent_angle)
    from the envelope words of ``ENVELOPE_PARAMS`` (cruise_airspeed, bank_limit, climb_rate,
    sink_rate) with their values."""
    airspeed = values["cruise_airspeed"]
    if not (math.isfinite(airspeed) and airspeed > 0):
        raise LinkError(f"the vehicle's cruise airspeed {airspeed!r} m/s is not a speed")
    out = {"cruise_airspeed": airspeed, "max_bank_angle": values["bank_limit"]}
    for word, key in (("climb_rate", "max_climb_angle"), ("sink_rate", "max_descent_angle")):
        rate = values[word]
        if not (math.isfinite(rate) and rate > 0):
            raise LinkError(f"the vehicle's {word.replace('_', ' ')} {rate!r} m/s is not a rate")
        out[key] = math.degrees(math.asin(min(1.0, rate / airspeed)))
    return out


def read_envelope(client: MissionClient) -> tuple[str, dict[str, float]]:
    """(firmware, planner overrides) read from the connected vehicle's parameters."""
    firmware = client.firmware if client.firmware in FIRMWARES else None
    if firmware is None:
        raise LinkError(
            f"the vehicle's autopilot is {client.firmware!r}: its parameter names are known for "
            f"{' and '.join(FIRMWARES)} only (give --firmware)"
        )
    target = client._target()
    values = {}
    for word, name in ENVELOPE_PARAMS[firmware].items():
        if word == "acceptance_radius":
            continue
        values[word] = read_parameter(
            client.link, target, name, timeout=client.timeout, retries=client.retries
        )
    return firmware, envelope_from_parameters(values)
