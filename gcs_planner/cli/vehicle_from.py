"""`--vehicle-from CONNECT`: the aircraft's envelope read from its autopilot's parameters, for the
commands that plan. Flags given on the command line win over what the autopilot says."""

from __future__ import annotations

import argparse
import sys


def add_vehicle_from_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--vehicle-from",
        metavar="CONN",
        help="read cruise airspeed, bank limit and climb/sink limits from the autopilot on this "
        "connection (its ArduPlane or PX4 parameters); flags given here win",
    )


def apply_vehicle_from(args: argparse.Namespace) -> None:
    """Fill the envelope flags the user left unset from the vehicle on ``args.vehicle_from``."""
    if not getattr(args, "vehicle_from", None):
        return
    # The link (pymavlink) loads only when an autopilot is asked: plan starts fast without it.
    from gcs_planner.cli.upload import connect_client
    from gcs_planner.link.envelope import read_envelope

    link_args = argparse.Namespace(
        connect=args.vehicle_from,
        baud=57600,
        signing_key=None,
        source_system=255,
        source_component=190,
        target_system=None,
        target_component=None,
        firmware=None,
        timeout=1.5,
        retries=5,
        wait=15.0,
        quiet=True,
    )
    client = connect_client(link_args)
    try:
        firmware, overrides = read_envelope(client)
    finally:
        client.link.close()
    if getattr(args, "turn_radius", None) is not None:
        overrides.pop("max_bank_angle")  # a radius given here wins over the autopilot's bank
    used = []
    for key, value in overrides.items():
        if getattr(args, key, None) is None:
            setattr(args, key, value)
            used.append(f"{key} {value:.4g}")
    print(f"gcs-planner: from the {firmware} vehicle: {', '.join(used)}", file=sys.stderr)
