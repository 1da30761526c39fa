"""`gcs-planner upload FILE --connect CONN`: send a mission to a vehicle and verify it."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

from gcs_planner.aircraft.autopilot import AUTOPILOTS
from gcs_planner.cli.common import add_autopilot_argument, add_quiet_argument, check_link_flags
from gcs_planner.errors import LinkError
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.mission_file import load_mission_file
from gcs_planner.link.params import set_parameter
from gcs_planner.link.progress import Progress
from gcs_planner.link.session import TRANSFERS, VERIFIES
from gcs_planner.link.signing import key_from_passphrase
from gcs_planner.link.vehicle_check import ParameterNeed, refusal, vehicle_shortfalls
from gcs_planner.mission import param_files
from gcs_planner.mission.param_files import SetupFile
from gcs_planner.mission.vehicle_setup import needs as setup_needs


def add_link_arguments(p: argparse.ArgumentParser) -> None:
    """The connection options every command that talks to a vehicle takes."""
    g = p.add_argument_group("link")
    g.add_argument(
        "--connect",
        required=True,
        metavar="CONN",
        help="pymavlink connection: udpin:0.0.0.0:14550, udpout:HOST:PORT, tcp:HOST:PORT, "
        "or a serial device such as /dev/ttyUSB0 (with --baud)",
    )
    g.add_argument("--baud", type=int, default=57600, help="serial baud rate (default 57600)")
    g.add_argument(
        "--signing-key",
        metavar="PASSPHRASE",
        help="MAVLink 2 signing passphrase (SHA-256 gives the key); unsigned peers are refused",
    )
    g.add_argument("--target-system", type=int, help="vehicle system id (default: first heard)")
    g.add_argument("--target-component", type=int, help="vehicle component id")
    g.add_argument(
        "--source-system",
        type=id_in(1, 255),
        default=255,
        help="our system id (default 255; give two ground stations different ids)",
    )
    g.add_argument(
        "--source-component",
        type=id_in(0, 255),
        default=190,
        help="our component id (default 190, MAV_COMP_ID_MISSIONPLANNER)",
    )
    add_autopilot_argument(g, help="the vehicle's autopilot (default: from its heartbeat)")
    g.add_argument(
        "--transfer",
        choices=TRANSFERS,
        default="auto",
        help="how missions travel: MAVFTP (@MISSION/mission.dat, ArduPilot), the mission "
        "protocol, or auto: MAVFTP when the vehicle offers it (default auto)",
    )
    g.add_argument("--timeout", type=float, default=1.5, help="seconds per wait (default 1.5)")
    g.add_argument("--retries", type=int, default=5, help="resends per wait (default 5)")
    g.add_argument(
        "--wait", type=float, default=15.0, help="seconds to wait for a heartbeat (default 15)"
    )
    add_quiet_argument(g)


def id_in(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: an integer MAVLink id in ``low..high``."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {low}..{high}, got {value}")
        return value

    return parse


def connect_client(args: argparse.Namespace) -> MissionClient:
    """Open the link, wait for the vehicle, return a client (the caller closes ``client.link``)."""
    check_link_flags(args)  # bad input, exit 2: before the link is opened
    key = key_from_passphrase(args.signing_key) if args.signing_key else None
    link = open_link(
        args.connect,
        baud=args.baud,
        signing_key=key,
        source_system=args.source_system,
        source_component=args.source_component,
    )
    quiet = args.quiet

    def progress(label: str, total: int) -> Progress:
        # Items done of the mission's count, with tqdm's rate and time left, on stderr.
        return Progress(label, total, stream=sys.stderr, enabled=False if quiet else None)

    client = MissionClient(
        link,
        target_system=args.target_system,
        target_component=args.target_component,
        # A caller's own namespace (plan --vehicle-from) may name no autopilot.
        firmware=getattr(args, "autopilot", None),
        timeout=args.timeout,
        retries=args.retries,
        progress=progress,
        transfer=getattr(args, "transfer", "auto"),
        verify=getattr(args, "verify", "crc"),
    )
    if not quiet:
        # Said at once: the wait may be long, and silence looks like a hang.
        print(
            f"waiting for a vehicle heartbeat on {args.connect} (up to {args.wait:g} s)...",
            file=sys.stderr,
            flush=True,
        )
    try:
        client.connect(timeout=args.wait)
    except BaseException:
        link.close()
        raise
    return client


def run(args: argparse.Namespace) -> int:
    mission = load_mission_file(args.file, firmware=args.autopilot, route_index=args.route_index)
    client = connect_client(args)
    try:
        vehicle = client.vehicle
        assert vehicle is not None
        if (
            Path(args.file).suffix.lower() in (".waypoints", ".json")
            and args.autopilot is None
            and vehicle.firmware in AUTOPILOTS
        ):
            # A .waypoints file does not say which firmware it was written for (its row 0 is
            # home either way), and a plan JSON is built into a mission here: both follow the
            # vehicle's firmware.
            mission = load_mission_file(
                args.file, firmware=vehicle.firmware, route_index=args.route_index
            )
        if (
            mission.firmware is not None
            and vehicle.firmware in AUTOPILOTS
            and mission.firmware != vehicle.firmware
        ):
            raise LinkError(
                f"{args.file} is a {mission.firmware} mission but the vehicle runs "
                f"{vehicle.firmware}: export it again with --autopilot {vehicle.firmware}"
            )
        if args.params is not None:
            _set_setup(client, args.params, vehicle.firmware)
        elif not args.no_param_check and Path(args.file).suffix.lower() == ".json":
            _check_parameters(client, args, vehicle.firmware)
        elif not args.no_param_check:
            _check_setup_beside(client, args.file, vehicle.firmware)
        radius = args.loiter_radius if args.loiter_radius is not None else mission.loiter_radius
        if args.keep_loiter_radius:
            radius = None
        if radius is not None:
            # Before anything is uploaded: a vehicle without the parameter would otherwise be
            # left holding a verified mission it will fly with tighter turns than planned.
            client.check_loiter_parameter()
        report = client.upload_verified(mission.items, loiter_radius=radius)
    finally:
        client.link.close()
    print(
        f"uploaded and verified {report.items} items to system {vehicle.system} "
        f"({vehicle.firmware}) in {report.seconds:.2f} s"
        + (" by MAVFTP" if report.transfer == "ftp" else "")
        + (" (checked by the vehicle's CRC of its mission file)" if report.verify == "crc" else "")
        + (f", {report.retries} resends" if report.retries else "")
        + (
            " (its final acknowledgement never came: the read-back shows it holds the mission)"
            if report.unacknowledged
            else ""
        )
    )
    if radius is not None:
        print(f"loiter radius set to {radius:g} m")
    return 0


def _check_parameters(client: MissionClient, args: argparse.Namespace, firmware: str) -> None:
    """Before anything is written: the vehicle's parameters against what the plan's envelope
    needs (``link.vehicle_check``); set them with ``--set-params`` (listed first), else refuse
    naming each parameter, its value and the plan's need."""
    # The plan JSON's reader imports the planner: loaded only for a plan JSON.
    from gcs_planner.mission.plan_json import load_plan

    if firmware not in AUTOPILOTS:
        return
    plan = load_plan(args.file)
    target = client._target()
    short = vehicle_shortfalls(
        client.link, target, plan, firmware, timeout=client.timeout, retries=client.retries
    )
    if not short:
        return
    if not args.set_params:
        raise LinkError(
            refusal(
                short,
                "set them with --set-params, or plan for this vehicle (plan --vehicle-from CONN)",
            )
        )
    for s in short:  # listed before anything is written
        print(
            f"will set {s.need.name} = {s.need.set_to:.4g} (is {s.value:g}): {s.need.why}",
            file=sys.stderr,
        )
    values = {s.need.name: s.need.set_to for s in short}
    _set_values(client, firmware, values, f"the {len(values)} the plan needs")
    print(f"set {len(short)} parameter(s) for the plan", file=sys.stderr)


def _set_values(client: MissionClient, firmware: str, values: dict[str, float], what: str) -> None:
    """Set each parameter (its MAVLink type from the autopilot's record) and read it back;
    refuse the upload naming every one the vehicle did not take."""
    ap = AUTOPILOTS.get(firmware)
    target = client._target()
    failed: list[str] = []
    for name, value in values.items():
        spec = ap.spec(name) if ap is not None else None
        try:
            set_parameter(
                client.link, target, name, value,
                *(() if spec is None else (spec.ptype,)),
                timeout=client.timeout, retries=client.retries,
            )  # fmt: skip
        except LinkError as exc:
            failed.append(f"{name} = {value:g} ({exc})")
    if failed:
        raise LinkError(
            f"the vehicle did not take {len(failed)} of {what}: "
            + "; ".join(failed)
            + ". Nothing was uploaded"
        )


def _setup_for(path: Path | str, firmware: str) -> SetupFile:
    """The setup file, refused when it is for another autopilot than the vehicle's."""
    setup = param_files.read(path)
    if setup.autopilot and firmware in AUTOPILOTS and setup.autopilot != firmware:
        raise LinkError(
            f"{path} is a vehicle setup for {setup.autopilot} but the vehicle runs {firmware}: "
            f"plan again with --autopilot {firmware}. Nothing was uploaded"
        )
    return setup


def _set_setup(client: MissionClient, path: Path, firmware: str) -> None:
    """``upload --params FILE``: set every parameter of the setup before the mission, read each
    back, and refuse the upload (nothing uploaded) naming those the vehicle did not take."""
    setup = _setup_for(path, firmware)
    what = f"the {len(setup.values)} parameters of {path}"
    _set_values(client, firmware, setup.values, what)
    print(f"set and read back {len(setup.values)} parameter(s) of {path}", file=sys.stderr)


def _check_setup_beside(client: MissionClient, mission: str, firmware: str) -> None:
    """A .plan or .waypoints with the setup ``plan --out`` wrote beside it: the vehicle's
    parameters against the plan's needs (plan.json beside it too), else against the file's
    values; refused naming each shortfall."""
    path = param_files.find_beside(mission)
    if path is None or firmware not in AUTOPILOTS:
        return
    setup = _setup_for(path, firmware)
    plan_path = Path(mission).parent / "plan.json"
    wanted = []
    if plan_path.is_file():
        from gcs_planner.mission.plan_json import load_plan

        plan = load_plan(str(plan_path))
        wanted = setup_needs(plan, firmware)
    if not wanted:
        wanted = [
            ParameterNeed(name, value, value, f"{path} sets it", most=value)
            for name, value in setup.values.items()
        ]
    target = client._target()
    short = vehicle_shortfalls(
        client.link, target, {}, firmware, timeout=client.timeout, retries=client.retries,
        wanted=wanted,
    )  # fmt: skip
    if short:
        raise LinkError(
            refusal(
                short,
                f"set them with --params {path} (or upload --no-param-check to fly it as it is)",
            )
        )


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "upload",
        help="upload a mission to a vehicle, read it back and compare",
        description="Upload a .plan, .waypoints or plan JSON over MAVLink, read it back and "
        "compare; a partial or different mission is an error (exit 4).",
    )
    p.add_argument("file", help="mission file: .plan, .waypoints or plan JSON")
    add_link_arguments(p)
    p.add_argument("--route-index", type=int, help="plan JSON: route of the front to upload")
    p.add_argument(
        "--loiter-radius",
        type=float,
        help="set the vehicle's loiter radius to this (default: the plan's turning radius)",
    )
    p.add_argument(
        "--keep-loiter-radius",
        action="store_true",
        help="leave the vehicle's loiter radius as it is (for vehicles without the parameter)",
    )
    p.add_argument(
        "--set-params",
        action="store_true",
        help="plan JSON: set the parameters the plan's envelope needs and the vehicle lacks "
        "(climb and sink rates, roll limit, ArduPlane NAVL1_LIM_BANK), listed before they are "
        "written; without it such a vehicle is refused and nothing is uploaded",
    )
    p.add_argument(
        "--params",
        type=Path,
        metavar="FILE",
        help="the vehicle setup to set before the mission (.param or .params, as plan --out "
        "writes it): each parameter set and read back; a vehicle that does not take one is "
        "refused and nothing is uploaded",
    )
    p.add_argument(
        "--no-param-check",
        action="store_true",
        help="do not check the vehicle's parameters against the plan's vehicle setup (found "
        "beside the mission, or in the plan JSON)",
    )
    p.add_argument(
        "--verify",
        choices=VERIFIES,
        default="crc",
        help="how an upload by MAVFTP is checked: crc asks the vehicle for the CRC-32 of the "
        "mission file it builds from what it stored and reads the mission back only when that "
        "does not match or is not answered; read always reads it back (default crc). The "
        "mission protocol is always checked by reading back",
    )
    p.set_defaults(func=run)


if __name__ == "__main__":  # pragma: no cover
    sys.exit("run as: gcs-planner upload")
