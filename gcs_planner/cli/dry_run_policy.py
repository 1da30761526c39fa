"""`gcs-planner dry-run SCENARIO --policy policy.json --runs N`: fly a contingency policy end to
end with the mock vehicle and the ground station in the loop (gcs_planner/policies/dry_run.py)."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict

from gcs_planner.cli.common import load_scenario_from_args
from gcs_planner.cli.fly import load_policy
from gcs_planner.errors import InputError, LinkError
from gcs_planner.mission import param_files
from gcs_planner.policies.dry_run import (
    PolicyDryRunReport,
    check_against_scenario,
    policy_dry_run,
    policy_probability,
    policy_switch_room,
)
from gcs_planner.policies.onboard_dry_run import check_onboard, load_applet, onboard_dry_run
from gcs_planner.sim.live_vehicle import DEFAULT_TIME_SCALE
from gcs_planner.sim.replay import DEFAULT_CAPTURE_RADIUS_M

EXIT_VERDICT = 5  # the dry run's: flown, but the verdict failed


def add_policy_arguments(g: argparse._ArgumentGroup) -> None:
    g.add_argument(
        "--policy",
        metavar="POLICY",
        help="fly this policy.json (plan --policy) instead of planning: each of --runs N "
        "flights with the ground station in the loop switching missions in flight",
    )
    g.add_argument(
        "--time-scale",
        default=str(DEFAULT_TIME_SCALE),
        metavar="X",
        help="--policy: simulated seconds per wall second the vehicle flies while the ground "
        f"station talks to it (default {DEFAULT_TIME_SCALE:g}); the window for a switch, in "
        "wall time, is the distance to the next item over the ground speed, divided by it",
    )
    g.add_argument(
        "--onboard",
        action="store_true",
        help="--policy: switch on board: the onboard mission and policy.lua (the file beside "
        "POLICY, else generated) on a mock ArduPilot, the ground link cut after take-off, flown "
        "in simulated time (--time-scale and --cruise-time-scale do not apply)",
    )
    g.add_argument(
        "--cruise-time-scale",
        metavar="Y",
        help="--policy: the time scale while no failed or missed fix awaits the ground station "
        "(default: --time-scale throughout); after such a fix the vehicle flies at --time-scale "
        "until an item is set current or it has reached two more items, so that every switch "
        "is flown as at --time-scale, and long flights take minutes, not hours",
    )


def run_policy(
    args: argparse.Namespace,
    number,  # noqa: ANN001 - cli.dry_run._number
    settings: dict[str, float],
) -> int:
    runs = int(number(args.runs, "--runs", int, 1))
    loss = number(args.loss, "--loss", float, 0.0, 1.0)
    seed = int(number(args.seed, "--seed", int, 0))
    scale = number(args.time_scale, "--time-scale", float, 0.01, 10_000.0)
    cruise = None
    if args.cruise_time_scale is not None:
        cruise = number(args.cruise_time_scale, "--cruise-time-scale", float, scale, 100_000.0)
    landmarks = load_scenario_from_args(args)
    policy = load_policy(args.policy)
    check_against_scenario(policy, landmarks, DEFAULT_CAPTURE_RADIUS_M, args.policy)
    probability = policy_probability(args.policy)
    quiet = args.json
    if args.onboard:
        check_onboard(policy, args.policy)
    # The operator's workflow: the vehicle setup plan --out wrote beside policy.json is set with
    # the missions (the user's own --param values win); --vehicle-as-is flies without it.
    setup_path = None if args.vehicle_as_is else param_files.find_beside(args.policy)
    if setup_path is not None:
        setup = param_files.read(setup_path)
        flavour = policy.missions[policy.primary].firmware
        if setup.autopilot and setup.autopilot != flavour:
            raise InputError(
                f"a vehicle setup for {setup.autopilot}, but the policy's missions are for "
                f"{flavour}: plan the policy again with --firmware {setup.autopilot}",
                file=str(setup_path),
            )
        settings = {**setup.values, **settings}
        if not quiet:
            print(f"gcs-planner: the vehicle setup {setup_path} is set with the missions",
                  file=sys.stderr)  # fmt: skip

    def say(line: str) -> None:
        if not quiet:
            print(f"  {line}", file=sys.stderr, flush=True)

    common = dict(
        runs=runs,
        probability=probability,
        loss=loss,
        seed=seed,
        navigate_on_estimate=not args.navigate_on_truth,
        say=say,
        set_params=settings,
        switch_room=policy_switch_room(args.policy),
    )
    if args.onboard:
        applet, source = load_applet(args.policy, policy, landmarks)
        say(f"the applet: {source}")
        report = onboard_dry_run(policy, landmarks, applet, **common)
    else:
        report = policy_dry_run(policy, landmarks, time_scale=scale, cruise_scale=cruise, **common)
    if args.json:
        out = asdict(report)
        out.update(
            successes=report.successes,
            success_rate=report.success_rate,
            success_ci=list(report.interval),
            ok=report.ok,
            probability_within_ci=report.probability_within_ci,
            longest_switch_m=report.longest_switch,
            switches_beyond_room=report.switches_beyond_room,
        )
        sys.stdout.write(json.dumps(out, indent=2) + "\n")
    else:
        print(render(report, args.policy))
    if report.link_failures:
        print(
            f"gcs-planner: error: {report.link_failures} of {len(report.runs)} run(s): the "
            "ground station failed (see the runs)",
            file=sys.stderr,
        )
        return LinkError.exit_code
    if not report.ok:
        print(
            "gcs-planner: verdict failed: the success rate is not consistent with the "
            "policy's probability",
            file=sys.stderr,
        )
        return EXIT_VERDICT
    return 0


def render(r: PolicyDryRunReport, source: str) -> str:
    low, high = r.interval
    how = f"{r.time_scale:g} simulated s per wall s"
    if r.onboard:
        how = "switched on board by its applet, the ground link cut after take-off, simulated time"
    out = [
        f"dry run of policy {source} on a mock {r.flavour} vehicle over UDP 127.0.0.1 (loss "
        f"{r.loss:g}, seed {r.seed}, {how})",
    ]
    for run in r.runs:
        verdict = "arrived" if run.arrived else f"NOT arrived: {run.why}"
        out.append(
            f"  run {run.seed}: {' -> '.join(run.missions_flown) or '-'}; met "
            f"{' '.join(run.points_met) or '-'}; {verdict}"
        )
    said = "the policy's probability not given (policy.json has no 'probability')"
    if r.probability is not None:
        within = "within" if r.probability_within_ci else "OUTSIDE"
        said = f"the policy's exact probability {r.probability:.4f}: {within} the interval"
    out.append(
        f"success rate {r.success_rate:.3f} over {len(r.runs)} flights "
        f"({r.confidence * 100:g} % Wilson interval {low:.3f}-{high:.3f}); {said}"
    )
    if r.link_failures:
        out.append(
            f"{r.link_failures} run(s) lost to the ground station's link (counted as not arrived)"
        )
    if r.switches:
        room = (
            "the policy keeps no switch room"
            if r.switch_room is None
            else f"the policy's switch room {r.switch_room:.0f} m"
        )
        out.append(
            f"{len(r.switches)} switch(es) set current, the farthest {r.longest_switch:.0f} m "
            f"flown after its fix ({room})"
        )
        if r.switches_beyond_room:
            out.append(
                f"WARNING: {r.switches_beyond_room} switch(es) beyond the switch room: the "
                "aircraft had left the run-out it shares with the branch (plan with a longer "
                "--switch-time, or fly at a smaller --time-scale)"
            )
    return "\n".join(out)


def refuse_plan_flags(args: argparse.Namespace) -> None:
    """--policy flies the policy's own missions: flags that shape a plan's flight are refused
    rather than ignored."""
    for flag, value in (("--track-out", args.track_out),):
        if value:
            raise InputError("not used with --policy", field=flag)
    for flag, value in (("--wind", args.wind), ("--gust", args.gust)):
        if value.strip() not in ("0", "0.0"):
            raise InputError("a policy is flown in still air (wind not modelled yet with "
                             "--policy)", field=flag)  # fmt: skip
