"""The aircraft in its autopilot's terms, for the commands that plan: cruise EAS, bank limit,
climb and sink rates and the autopilot, from flags, ``--vehicle-from CONNECT`` (the autopilot's
own parameters) or the autopilot's shipped defaults (``--firmware``), and the design wind
(``--wind``). From them the envelope the legs use (turning radius, climb and descent angles) is
derived (:class:`gcs_planner.aircraft.profile.DerivedEnvelope`); ``--turn-radius``,
``--max-climb-angle``
and ``--max-descent-angle`` remain direct statements of the envelope and win over derivation.
Flags given on the command line win over what the autopilot says."""

from __future__ import annotations

import argparse
import math
import sys

from gcs_planner.aircraft.autopilot import autopilot_for, effective
from gcs_planner.aircraft.derive import derive_envelope, with_derived_reserve
from gcs_planner.aircraft.profile import FIRMWARES
from gcs_planner.cli.common import add_autopilot_argument

__all__ = [
    "add_envelope_arguments",
    "add_vehicle_from_argument",
    "apply_vehicle_from",
    "derive_envelope",
    "with_derived_reserve",
]


def add_vehicle_from_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--vehicle-from",
        metavar="CONN",
        help="read cruise airspeed, bank limit and climb/sink rates from the autopilot on this "
        "connection (its ArduPlane or PX4 parameters; PX4: the mission rates); flags given win",
    )


def add_envelope_arguments(
    p: argparse.ArgumentParser, *, wind: bool = True, autopilot: bool = True
) -> None:
    """The autopilot's terms the envelope is derived from (plan; dry-run has its own --wind and
    --autopilot, which it passes in)."""
    g = p.add_argument_group("the aircraft in its autopilot's terms (derive the envelope)")
    g.add_argument(
        "--max-climb-rate", type=float, metavar="M/S", help="climb rate a mission climbs at"
    )
    g.add_argument(
        "--max-sink-rate", type=float, metavar="M/S", help="sink rate a mission descends at"
    )
    g.add_argument(
        "--per-leg-envelope",
        action="store_true",
        help="each leg on the turning radius (ArduPlane: and the climb and descent angles) of "
        "the TAS at its own highest point, not the scenario's highest: shorter routes that the "
        "derived flight reserve does not yet cover everywhere (docs/model.md); dry-run them",
    )
    if autopilot:
        add_autopilot_argument(
            g,
            help="the autopilot that flies the plan (default: ardupilot): its shipped defaults "
            "fill the cruise airspeed, bank limit and climb/sink rates not given otherwise",
        )
    if wind:
        g.add_argument(
            "--wind",
            metavar="SPEED[@FROM_DEG]",
            help="design wind, m/s: the envelope holds in a wind of this speed from any "
            "direction; with @FROM_DEG and the angles from rates, each leg climbs and "
            "descends within the limits of its own ground track",
        )
        g.add_argument(
            "--gust",
            type=float,
            metavar="SPEED",
            help="design gusts, m/s per horizontal axis: the derived flight reserve covers the "
            "track they lengthen (default 0)",
        )


def apply_vehicle_from(args: argparse.Namespace) -> None:
    """Fill the autopilot-term flags the user left unset from the vehicle on
    ``args.vehicle_from``: cruise airspeed, bank limit and the rates a mission flies with
    (:func:`gcs_planner.aircraft.autopilot.effective`: ArduPlane TECS_CLMB_MAX / TECS_SINK_MAX; PX4
    min(FW_T_CLMB_R_SP, FW_T_CLMB_MAX) and min(FW_T_SINK_R_SP, FW_T_SINK_MAX), the rates its
    position controller gives TECS in missions)."""
    if not getattr(args, "vehicle_from", None):
        return
    # The link (pymavlink) loads only when an autopilot is asked: plan starts fast without it.
    from gcs_planner.cli.upload import connect_client
    from gcs_planner.errors import LinkError
    from gcs_planner.link.params import read_parameter

    link_args = argparse.Namespace(
        connect=args.vehicle_from,
        baud=57600,
        signing_key=None,
        source_system=255,
        source_component=190,
        target_system=None,
        target_component=None,
        autopilot=None,
        timeout=1.5,
        retries=5,
        wait=15.0,
        quiet=True,
    )
    client = connect_client(link_args)
    try:
        firmware = client.firmware if client.firmware in FIRMWARES else None
        if firmware is None:
            raise LinkError(
                f"the vehicle's autopilot is {client.firmware!r}: its parameter names are known "
                f"for {' and '.join(FIRMWARES)} only"
            )
        ap = autopilot_for(firmware)
        names = [ap.envelope["cruise_airspeed"], ap.envelope["bank_limit"]]
        names += [*ap.mission_climb, *ap.mission_climb_bounds, *ap.guidance]
        target = client._target()
        values = {
            name: read_parameter(
                client.link, target, name, timeout=client.timeout, retries=client.retries
            )
            for name in names
        }
    finally:
        client.link.close()
    eff = effective(firmware, values)
    for name in ap.guidance:
        spec = ap.spec(name)
        assert spec is not None  # every guidance parameter is in the autopilot's table
        if not (math.isfinite(values[name]) and spec.low <= values[name] <= spec.high):
            raise LinkError(
                f"the vehicle's {name} {values[name]!r} lies outside {spec.low:g}..{spec.high:g}"
            )
    overrides = {
        "cruise_airspeed": eff.cruise_airspeed,
        "max_bank_angle": eff.bank_limit,
        "max_climb_rate": eff.climb_rate,
        "max_sink_rate": eff.sink_rate,
    }
    for key, value in overrides.items():
        if not (math.isfinite(value) and value > 0):
            raise LinkError(f"the vehicle's {key.replace('_', ' ')} {value!r} is not usable")
    if getattr(args, "turn_radius", None) is not None:
        overrides.pop("max_bank_angle")  # a radius given here wins over the autopilot's bank
    used = []
    for key, value in overrides.items():
        if getattr(args, key, None) is None:
            setattr(args, key, value)
            used.append(f"{key} {value:.4g}")
    if getattr(args, "autopilot", None) is None:
        args.autopilot = firmware
    args.vehicle_source = f"the {firmware} vehicle"
    # Its path follower's tuning: the runs and the reserve are derived from it, not from the
    # shipped defaults, when the plan is for this autopilot.
    args.vehicle_values = (firmware, {name: values[name] for name in ap.guidance})
    tuning = ", ".join(f"{name} {values[name]:g}" for name in ap.guidance)
    print(
        f"gcs-planner: from the {firmware} vehicle: {', '.join(used)}; guidance {tuning}",
        file=sys.stderr,
    )
