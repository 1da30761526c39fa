"""`gcs-planner mock-vehicle --connect CONN --scenario SCENARIO`: a simulated autopilot any ground
station can talk to, until Ctrl-C. It stores what it is sent and, on MAV_CMD_MISSION_START,
flies it against the scenario's correction points with telemetry.

With ``--radio sik[:AIR_RATE]`` the ground station reaches it through an emulated SiK radio pair
(:mod:`sim.radio`): CONN is then the ground radio's side, either end (``udpin``: the ground
station speaks first; ``udpout``: the radio sends there), and the air radio listens on a free
port of 127.0.0.1 for the vehicle, which sends to it as an autopilot writes to its radio's
serial port. (A vehicle that listened behind the air radio could only answer once it heard a
frame, and with CONN ``udpout`` the ground station listens too: neither spoke first.)

The ArduPilot mock serves MAVLink FTP (:mod:`sim.ftp_server`, ``@MISSION/mission.dat``) and
advertises it in AUTOPILOT_VERSION; ``--no-ftp`` is an ArduPilot built without it."""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Callable

from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT
from gcs_planner.cli.common import (
    add_autopilot_argument,
    add_scenario_arguments,
    load_scenario_from_args,
)
from gcs_planner.cli.upload import id_in
from gcs_planner.errors import InputError
from gcs_planner.link.connection import check_connection
from gcs_planner.link.signing import key_from_passphrase
from gcs_planner.scenario.model import Scenario
from gcs_planner.sim.faults import FaultRates
from gcs_planner.sim.radio import RadioConfig, SikRadio, parse_radio
from gcs_planner.sim.replay import DEFAULT_CAPTURE_RADIUS_M
from gcs_planner.sim.vehicle import MockVehicle


def _rate(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a rate in [0, 1], got {text!r}") from None
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"expected a rate in [0, 1], got {text!r}")
    return value


def _speedup(text: str | float) -> float:
    """--speedup, checked in ``run`` (not by argparse, whose refusal prints the whole usage):
    InputError naming the flag, one line and exit 2."""
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"not a number: {text!r}", field="--speedup") from None
    if not (value >= 0 and value < float("inf")):
        raise InputError(
            f"must be a finite number >= 0 (1: real time; 0: as fast as the link takes it), "
            f"got {text!r}",
            field="--speedup",
        )
    return value


def _count(low: int, what: str) -> Callable[[str], int]:
    """An argparse type: a whole number >= ``low`` (refused by argparse with one line)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"expected {what} >= {low}, got {text!r}")
        return value

    return parse


def _radio_kind(text: str) -> int:
    try:
        return parse_radio(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _loss(text: str) -> float:
    value = _rate(text)
    if value >= 1.0:
        raise argparse.ArgumentTypeError("a radio that loses every packet carries nothing")
    return value


def _burst(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 1, got {text!r}") from None
    if not value >= 1.0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number >= 1 (packets), got {text!r}")
    return value


def _check_radio_end(connect: str) -> None:
    if connect.partition(":")[0].lower() not in ("udpin", "udpout"):
        raise InputError(
            "--radio runs the radio pair as a UDP relay: --connect must be udpin:HOST:PORT "
            "or udpout:HOST:PORT (the ground radio's side)",
            field="--connect",
        )


def _radio(args: argparse.Namespace) -> SikRadio:
    """The radio pair for ``--radio`` (not started): the ground side on ``--connect``, the air
    side listening on a free port of 127.0.0.1 for the vehicle."""
    config = RadioConfig(
        air_rate=args.radio,
        serial_baud=args.baud,
        loss=args.radio_loss,
        burst=args.radio_burst,
        seed=args.seed,
    )
    try:
        return SikRadio(args.connect, "udpin:127.0.0.1:0", config)
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot start the radio on {args.connect}: {exc}") from None


def _vehicle(args: argparse.Namespace, scenario: Scenario, connect: str) -> MockVehicle:
    faults = FaultRates(
        drop=args.drop, duplicate=args.duplicate, delay=args.delay, reorder=args.reorder
    )
    vehicle = MockVehicle(
        connect,
        scenario=scenario,
        flavour=args.autopilot,
        system_id=args.system_id,
        component_id=args.component_id,
        capacity=args.capacity,
        faults_out=faults if args.faults_on in ("out", "both") else None,
        faults_in=faults if args.faults_on in ("in", "both") else None,
        fault_seed=args.seed,
        signing_key=key_from_passphrase(args.signing_key) if args.signing_key else None,
        capture_radius=args.capture_radius,
        baud=args.baud,
        speedup=args.speedup or None,
        live=args.live,
    )
    vehicle.ftp_enabled = not args.no_ftp
    return vehicle


def run(args: argparse.Namespace) -> int:
    check_connection(args.connect)  # a typo is named before the scenario is read
    args.speedup = _speedup(args.speedup)
    if args.radio is not None:
        _check_radio_end(args.connect)
    scenario = load_scenario_from_args(args, args.scenario)
    radio = _radio(args) if args.radio is not None else None
    try:
        vehicle = _vehicle(args, scenario, radio.vehicle_connection if radio else args.connect)
    except BaseException:
        if radio is not None:
            radio.stop()
        raise
    if radio is not None:
        radio.start()
        t, config = radio.timing, radio.config
        print(
            f"through a SiK radio pair at {config.air_rate} kbit/s (TDM windows "
            f"{t.window_s * 1000:.0f} ms), serial {config.serial_baud} baud, "
            f"{config.loss:.0%} burst loss (mean burst {config.burst:g} packets)",
            file=sys.stderr,
        )
    print(
        f"mock vehicle ({args.autopilot}, system {args.system_id}) on {args.connect} with "
        f"{scenario.n} landmarks from {scenario.source}; Ctrl-C to stop",
        file=sys.stderr,
    )

    # Ctrl-C and a process manager's SIGTERM end the loop at its next turn (within ~10 ms)
    # instead of raising wherever the main thread happens to be.
    def request_stop(signum: int, frame: object) -> None:
        vehicle.request_stop()

    previous = {sig: signal.signal(sig, request_stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        vehicle.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        vehicle.stop()
        if radio is not None:
            radio.stop()
    print(f"mock vehicle stopped; it holds {len(vehicle.mission)} items", file=sys.stderr)
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "mock-vehicle",
        help="run a simulated fixed-wing autopilot for a ground station to talk to",
        description="The vehicle side of the MAVLink mission protocol, with the scenario's "
        "correction points as its landmark database; runs until Ctrl-C.",
    )
    p.add_argument("--connect", required=True, metavar="CONN", help="e.g. udpin:0.0.0.0:14550")
    p.add_argument("--scenario", required=True, help="scenario file: .toml, .csv or .xlsx")
    add_scenario_arguments(p, positional=False)
    add_autopilot_argument(
        p,
        help="the autopilot the mock vehicle is (default ardupilot): its mission protocol, "
        "parameters and navigation",
        default=DEFAULT_AUTOPILOT,
        old=("--flavour", "--firmware"),
    )
    p.add_argument(
        "--system-id", "--source-system", dest="system_id", type=id_in(1, 255), default=1
    )
    p.add_argument(
        "--component-id",
        "--source-component",
        dest="component_id",
        type=id_in(1, 255),
        default=1,
        help="autopilot component id (default 1, MAV_COMP_ID_AUTOPILOT1)",
    )
    p.add_argument("--capacity", type=_count(0, "items"), default=5000, help="most items it stores")
    p.add_argument("--baud", type=_count(1, "a baud rate"), default=57600)
    p.add_argument("--signing-key", metavar="PASSPHRASE", help="sign and require signatures")
    p.add_argument(
        "--capture-radius",
        type=float,
        default=DEFAULT_CAPTURE_RADIUS_M,
        help="landmark CAPTURE radius (3D, metres) within which a correction works "
        f"(default {DEFAULT_CAPTURE_RADIUS_M:g})",
    )
    p.add_argument(
        "--speedup",
        default=100.0,
        metavar="N",
        help="a flight started by MISSION_START plays N times faster than real time "
        "(1: real time; 0: as fast as the link takes it; default 100)",
    )
    p.add_argument(
        "--live",
        action="store_true",
        help="fly the mission as it is played, following missions uploaded and items set "
        "current in flight (what `gcs-planner fly` needs; docs/flying-policies.md); the "
        "speedup is then the flight's time scale (0 is taken as 20)",
    )
    p.add_argument(
        "--no-ftp",
        action="store_true",
        help="serve no MAVFTP (ArduPilot serves its mission as @MISSION/mission.dat by default)",
    )
    r = p.add_argument_group("radio (sim/radio.py; seeded by --seed)")
    r.add_argument(
        "--radio",
        type=_radio_kind,
        metavar="sik[:AIR_RATE]",
        help="reach the vehicle through an emulated SiK radio pair: half-duplex TDM at "
        "AIR_RATE kbit/s (default 64), serial at --baud, SiK's buffers, RADIO_STATUS",
    )
    r.add_argument(
        "--radio-loss", type=_loss, default=0.0, help="mean air packet loss in [0, 1) (bursts)"
    )
    r.add_argument(
        "--radio-burst", type=_burst, default=4.0, help="mean loss burst, packets (default 4)"
    )
    g = p.add_argument_group("fault injection (seeded)")
    for name in ("drop", "duplicate", "delay", "reorder"):
        g.add_argument(f"--{name}", type=_rate, default=0.0, help=f"{name} rate in [0, 1]")
    g.add_argument("--faults-on", choices=("out", "in", "both"), default="both")
    g.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=run)
