"""`gcs-planner fly POLICY --connect CONN`: the ground station in the loop that flies a
contingency policy (gcs_planner/policies/flight.py)."""

from __future__ import annotations

import argparse
import sys

from gcs_planner.aircraft.autopilot import AUTOPILOTS
from gcs_planner.cli.upload import add_link_arguments, connect_client
from gcs_planner.errors import InputError, LinkError
from gcs_planner.mission.policy_missions import PolicyMissions
from gcs_planner.policies.flight import DEFAULT_SILENCE_S, PolicyFlight, check_policy

EPILOG = f"""exit codes: 0 the flight is over (the vehicle disarmed) with every switch the policy
called for made and confirmed; 2 bad input (a policy file that does not hold together, or whose
missions are for another firmware); {LinkError.exit_code} the link failed: a mission that could
not be uploaded or verified (the message says which mission the vehicle holds and flies), a
current item not confirmed, or a vehicle that stopped reporting."""


def load_policy(path: str) -> PolicyMissions:
    """The policy file's missions and switches, checked (one line and exit 2 when bad)."""
    try:
        # The exporter's reader (plan --policy writes policy.json); imported here so that
        # `fly --help` needs none of it.
        from gcs_planner.mission.policy_file import read_policy
    except ImportError:
        raise InputError(
            "this build cannot read policy files (no policy_file module)", file=path
        ) from None
    try:
        policy = read_policy(path)
    except OSError as exc:
        raise InputError(f"cannot read it: {exc.strerror}", file=path) from None
    check_policy(policy, path)
    return policy


def run(args: argparse.Namespace) -> int:
    if not args.silence > 0:
        raise InputError(f"must be > 0, got {args.silence!r}", field="--silence")
    if args.attempts < 1:
        raise InputError(f"must be >= 1, got {args.attempts!r}", field="--attempts")
    policy = load_policy(args.policy)
    firmware = policy.missions[policy.primary].firmware
    client = connect_client(args)
    try:
        vehicle = client.vehicle
        assert vehicle is not None
        if vehicle.firmware in AUTOPILOTS and vehicle.firmware != firmware:
            raise InputError(
                f"the policy's missions are for {firmware} but the vehicle runs "
                f"{vehicle.firmware}: export them again for it",
                file=args.policy,
            )

        def say(line: str) -> None:
            print(line, flush=True)

        if args.onboard:
            # The companion on the vehicle's local link (policies/companion.py).
            from gcs_planner.policies.companion import CompanionFlight

            flight: PolicyFlight = CompanionFlight(client, policy, say=say, silence=args.silence)
        else:
            flight = PolicyFlight(
                client, policy, say=say, silence=args.silence, attempts=args.attempts
            )
        outcome = flight.run(start=args.start, start_wait=args.start_wait)
    finally:
        client.link.close()
    print(
        f"flown: {' -> '.join(outcome.missions_flown)}; {len(outcome.reports)} correction "
        f"report(s), {outcome.switches} switch(es)"
    )
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "fly",
        help="fly a contingency policy: upload, watch the corrections, switch missions in flight",
        description="Upload and verify the policy's primary mission, start it (--start) or wait "
        "for the operator to, then watch the vehicle's correction reports (STATUSTEXT 'V fix "
        "<point> FAILED', docs/flying-policies.md); when a fix fails where the policy "
        "branches, upload the branch's mission, verify it, set its resume item current and "
        "confirm it. One line per event.",
        epilog=EPILOG,
    )
    p.add_argument("policy", help="policy.json, as plan --policy writes it")
    add_link_arguments(p)
    g = p.add_argument_group("flight")
    g.add_argument(
        "--onboard",
        action="store_true",
        help="switch on board, as a companion computer on the vehicle's local link (PX4, which "
        "runs no applets; the ground link is optional): hold the onboard mission (every "
        "branch in one, uploaded and verified unless the vehicle holds it) and set a branch's "
        "first item current when a fix fails, as policy.lua does on ArduPilot",
    )
    g.add_argument(
        "--start",
        action="store_true",
        help="start the mission (MAV_CMD_MISSION_START) once it is verified; "
        "otherwise wait for the operator to start it",
    )
    g.add_argument(
        "--start-wait",
        type=float,
        default=600.0,
        metavar="SECONDS",
        help="how long to wait for the mission to start (default 600)",
    )
    g.add_argument(
        "--silence",
        type=float,
        default=DEFAULT_SILENCE_S,
        metavar="SECONDS",
        help="a vehicle silent this long has stopped reporting: exit "
        f"{LinkError.exit_code} (default {DEFAULT_SILENCE_S:g})",
    )
    g.add_argument(
        "--attempts",
        type=int,
        default=3,
        help="whole uploads tried per mission before giving up (default 3)",
    )
    p.set_defaults(func=run)


if __name__ == "__main__":  # pragma: no cover
    sys.exit("run as: gcs-planner fly")
