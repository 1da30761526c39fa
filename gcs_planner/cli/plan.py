"""`gcs-planner plan SCENARIO`: the Pareto front and the chosen route's table."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT
from gcs_planner.aircraft.derive import design_wind_speed
from gcs_planner.cli.common import (
    add_plan_arguments,
    add_scenario_arguments,
    load_scenario_from_args,
    plan_from_args,
)
from gcs_planner.cli.from_state import add_from_state_arguments, apply_from_state
from gcs_planner.cli.vehicle_from import (
    add_envelope_arguments,
    add_vehicle_from_argument,
    apply_vehicle_from,
    derive_envelope,
)
from gcs_planner.core.replan import DEFAULT_POLICY_LEVELS
from gcs_planner.mission.param_files import render_setup
from gcs_planner.mission.vehicle_setup import needs as setup_needs
from gcs_planner.mission.vehicle_setup import setup_lines, setup_to_dict
from gcs_planner.runtime.atomic import check_output_dir

if TYPE_CHECKING:
    from gcs_planner.aircraft.altitude_hold import AltitudeHold
    from gcs_planner.aircraft.reserve import DerivedReserve
    from gcs_planner.core.planner import Plan
    from gcs_planner.core.route import Route
    from gcs_planner.core.switch_room import SwitchRoom
    from gcs_planner.scenario.model import Scenario


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan",
        help="plan a scenario: the exact Pareto front and one chosen route",
        description="Compute the Pareto front of INS-feasible routes and choose one.",
    )
    add_scenario_arguments(p)
    add_plan_arguments(p)
    add_vehicle_from_argument(p)
    add_envelope_arguments(p)
    add_from_state_arguments(p)
    p.add_argument(
        "--endurance",
        metavar="MINUTES",
        help="the minutes of flight the aircraft has (default the scenario's [vehicle] "
        "endurance, else unlimited): only routes whose flight time in the design wind is within "
        'it are planned (docs/model.md, "Endurance in the plan")',
    )
    p.add_argument("--json", action="store_true", help="print one JSON object, nothing else")
    p.add_argument(
        "--aircraft",
        metavar="NAME",
        help="a JSBSim airframe (the project's aerosonde, or one the jsbsim package ships): the "
        "cruise airspeed, bank and climb/sink rates not given otherwise come from its trims at "
        "the scenario's highest point, within the autopilot's limits (docs/jsbsim.md)",
    )
    p.add_argument(
        "--turbulence",
        metavar="SIGMA_W|LEVEL",
        help="design vertical turbulence (Dryden, MIL-F-8785C: sigma_w m/s or light, moderate, "
        "severe): each capture gets a vertical allowance for the autopilot's altitude-hold error "
        "in it (docs/model.md); default the scenario's [environment] turbulence, else none",
    )
    p.add_argument(
        "--out",
        type=Path,
        help="folder for plan.json, the mission files, the route table and the pictures",
    )
    p.add_argument(
        "--allow-risky",
        action="store_true",
        help="with --out, write the mission even when the chosen route is less likely to arrive "
        "than --min-probability (a warning names its probability)",
    )
    p.add_argument(
        "--policy",
        action="store_true",
        help="with --out, replan the chosen route at each failed fix and write the contingency "
        "policy: primary.plan and one branch-<point>.plan per failure branch, policy.json (the "
        "switches between them), pictures of it, and for switching on board onboard.plan (every "
        "mission in one) with policy.lua (ArduPilot's applet)",
    )
    p.add_argument(
        "--policy-levels",
        type=int,
        default=DEFAULT_POLICY_LEVELS,
        metavar="N",
        help="with --policy, replan failure branches again at their own unreliable points, N "
        f"levels deep (default {DEFAULT_POLICY_LEVELS}: the route's own failures and its "
        "branches'; 1: the route's own failures only)",
    )
    p.add_argument(
        "--switch-time",
        default=None,
        metavar="SECONDS",
        help="with --policy, seconds from a failed fix to the branch flying: default 1, what "
        "switching on board needs (the report, one tick of policy.lua); 10 for a ground "
        "station that uploads each branch (fly without --onboard). Every run-out is planned at "
        "least this long at the largest ground speed, plus the capture radius, so the switch "
        "happens on it",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from gcs_planner.core.choose import check_exportable
    from gcs_planner.mission import plan_json

    if args.policy_levels < 1:
        from gcs_planner.errors import InputError

        raise InputError(f"must be >= 1, not {args.policy_levels}", field="--policy-levels")
    switch_seconds = _switch_time(args)
    from gcs_planner.cli.common import check_plan_flags

    check_plan_flags(args)  # --objectives, --max-corrections, ...: before the scenario is read
    if args.policy and not args.out:
        from gcs_planner.errors import InputError

        raise InputError("--policy writes missions: give --out DIR", field="--policy")
    if args.out:
        from gcs_planner.mission.export import ALL_FILES

        names: tuple[str, ...] | list[str] = ALL_FILES
        if args.policy:
            from gcs_planner.mission.policy_export import replaceable

            names = replaceable(args.out, ALL_FILES)
        check_output_dir(args.out, replaceable=names)  # before the search, not after it
    apply_vehicle_from(args)
    scenario = load_scenario_from_args(args)
    # The autopilot the plan is for (ArduPilot unless --autopilot): its path follower sets the
    # straight runs at the landmarks, and the vehicle setup names its parameters.
    autopilot = args.autopilot or DEFAULT_AUTOPILOT
    if args.aircraft is not None:
        # The airframe's own trims fill the autopilot terms left unset (issue 52).
        from gcs_planner.aircraft.airframe_trim import (
            apply_airframe_trims,
            highest_altitude,
            with_angle_flags,
        )

        apply_airframe_trims(args, highest_altitude(scenario), autopilot, scenario)
        scenario = with_angle_flags(args, scenario)  # climbs cut to the airframe's
    scenario = derive_envelope(args, scenario, wind_text=args.wind, flown_by=autopilot)
    scenario = apply_from_state(args, scenario)
    scenario = _with_endurance(args, scenario)
    hold = _design_hold(args, scenario, autopilot)
    if hold is not None:  # each capture's vertical allowance, kept to in the search
        from gcs_planner.core.capture import with_design_turbulence

        scenario = with_design_turbulence(scenario, hold)
    room = None
    if args.policy:
        scenario, room = _switch_room(scenario, switch_seconds)
    result = plan_from_args(args, scenario)
    plan_dict = plan_json.plan_to_dict(result)
    if hold is not None:
        from gcs_planner.aircraft.profile import TRACKING_ALLOWANCE_M
        from gcs_planner.core.capture import turbulence_capture

        stops = result.route.stops
        plan_dict["capture"] = turbulence_capture(stops, scenario, TRACKING_ALLOWANCE_M, hold)
    setup = setup_needs(plan_dict, autopilot, design_wind_speed(args, scenario))
    plan_dict["setup"] = setup_to_dict(setup, autopilot)
    text = plan_json.dumps_dict(plan_dict)
    if args.json:
        sys.stdout.write(text)
    else:
        print(render(result, plan_dict["capture"]))
        print("\n" + "\n".join(setup_lines(setup, autopilot)))
    if not args.out:
        return 0
    policy = None
    if args.policy:
        from gcs_planner.mission.policy_export import make_policy

        # The missions for the autopilot the plan is for (its onboard switching too).
        policy = make_policy(result, plan_dict, levels=args.policy_levels, firmware=autopilot)
        if room is not None:
            from dataclasses import replace

            policy = replace(policy, switch_room=room)
        if not args.json:
            from gcs_planner.mission.policy_export import summary

            print("\n" + summary(result, policy))
    # Refused after the front is shown, so the user sees what else there is to choose from.
    if policy is None:
        warning = check_exportable(
            result.route.probability, result.chosen, result.min_probability, args.allow_risky
        )
    else:  # what is flown is the policy: its probability is the one checked
        from gcs_planner.mission.policy_export import check_policy_exportable

        warning = check_policy_exportable(policy, result.min_probability, args.allow_risky)
    capture = plan_dict["capture"]["warning"]
    if policy is not None and policy.capture_warnings:
        branches = "; ".join(policy.capture_warnings)
        capture = f"{capture}; {branches}" if capture else branches
    if capture and not args.allow_risky:
        # A correction point the true track may pass outside its capture radius: the mission is
        # likely lost there, so it is not handed out without being asked for.
        from gcs_planner.core.choose import RiskyRouteError

        raise RiskyRouteError(f"{capture}; not exported: pass --allow-risky to export it anyway")
    if capture:
        warning = f"{warning}; {capture}" if warning else capture
    unflyable = [f"{n.name}: {n.impossible}" for n in setup if n.impossible]
    if unflyable:
        # No value of the autopilot's parameters flies it: not handed out unasked.
        cannot = f"no {autopilot} setup flies this plan ({'; '.join(unflyable)})"
        if not args.allow_risky:
            from gcs_planner.core.choose import RiskyRouteError

            raise RiskyRouteError(
                f"{cannot}; not exported: state the aircraft's climb limits (max_climb_angle, "
                "max_descent_angle) so the plan keeps to what it flies, or pass --allow-risky"
            )
        warning = f"{warning}; {cannot}" if warning else cannot
    extra: list[tuple[str, str | bytes]] = render_setup(setup, autopilot, str(args.scenario))
    if policy is not None:
        from gcs_planner.mission.policy_export import render_policy_files

        extra += render_policy_files(result, plan_dict, policy)
    written = write_outputs(result, plan_dict, text, args.out, extra, autopilot)
    if not args.json:
        print(f"\nwrote {', '.join(str(p) for p in written)}")
    if warning:
        print(f"gcs-planner: warning: {warning}", file=sys.stderr)
    if scenario.origin is None:
        from gcs_planner.scenario.georef import DEFAULT_ORIGIN_WARNING

        print(f"gcs-planner: warning: {DEFAULT_ORIGIN_WARNING}", file=sys.stderr)
    return 0


def _with_endurance(args: argparse.Namespace, scenario: Scenario) -> Scenario:
    """The scenario with the endurance of --endurance, else of its [vehicle] endurance."""
    from dataclasses import replace

    from gcs_planner.dryrun.endurance import vehicle_endurance

    endurance = vehicle_endurance(args.endurance, args.scenario)
    return scenario if endurance is None else replace(scenario, endurance=endurance)


def write_outputs(
    result: Plan,
    plan_dict: dict,
    text: str,
    out: Path,
    extra: list | None = None,
    autopilot: str = DEFAULT_AUTOPILOT,
) -> list[Path]:
    """plan.json and the vehicle setup beside the mission files of the chosen route for
    ``autopilot`` (default mission options; the `export` command takes the others), written as
    one folder: all of it or none (a Ctrl-C part-way leaves the previous folder, or none)."""
    from gcs_planner.mission.export import write_all

    files = (("plan.json", text), *(extra or ()))
    return write_all(plan_dict, out, extra=files, firmware=autopilot)


COLUMNS = (
    ("#", "{:>3}"),
    ("point", "{:>6}"),
    ("kind", "{:>4}"),
    ("leg m", "{:>10.1f}"),
    ("arc m", "{:>7.1f}"),
    ("turn °", "{:>6.1f}"),
    ("path °", "{:>6.1f}"),
    ("helix", "{:>5}"),
    ("total m", "{:>10.1f}"),
    ("v err", "{:>7.3f}"),
    ("h err", "{:>7.3f}"),
    ("v margin", "{:>8.3f}"),
    ("h margin", "{:>8.3f}"),
    ("P arrive", "{:>8.4f}"),
)


def table_rows(route: Route) -> list[list]:
    rows = []
    for n, s in enumerate(route.stops):
        leg = s.leg.length if s.leg else 0.0
        arc = s.leg.arc if s.leg else 0.0
        turn = math.degrees(s.leg.turn_angle) if s.leg else 0.0
        path = s.leg.path_angle if s.leg else 0.0
        helix = s.leg.helix_turns if s.leg else 0
        vm = s.v_margin if math.isfinite(s.v_margin) else float("nan")
        hm = s.h_margin if math.isfinite(s.h_margin) else float("nan")
        kind = s.kind.name + ("*" if s.unreliable else "")
        rows.append(
            [
                n,
                s.id,
                kind,
                leg,
                arc,
                turn,
                path,
                helix,
                s.cumulative,
                s.v_arrival,
                s.h_arrival,
                vm,
                hm,
                s.p_arrive,
            ]
        )
    return rows


def render_table(route: Route) -> str:
    head = " ".join(
        f"{name:>{len(fmt.format(0) if 'f' not in fmt else fmt.format(0.0))}}"
        for name, fmt in COLUMNS
    )
    lines = [head]
    for row in table_rows(route):
        cells = []
        for (_, fmt), value in zip(COLUMNS, row):
            cell = fmt.format(value)
            cells.append(cell.replace("nan", "  -"))
        lines.append(" ".join(cells))
    return "\n".join(lines)


def reserve_line(reserve: float, basis: DerivedReserve | None = None) -> str:
    """What the flight reserve promises, in the operator's words, and why it is that large."""
    if reserve > 0 and basis is not None:
        return f"flight reserve: {reserve:,.0f} m, {basis.describe()}; --reserve M states it"
    if reserve > 0:
        return (
            f"flight reserve: {reserve:,.0f} m (every error stays within its limit for a flight up "
            f"to {reserve:,.0f} m longer than planned between two corrections; --reserve 0 "
            "plans to the limits)"
        )
    return "flight reserve: none (the limits are planned to the metre: --reserve M keeps a margin)"


def reserve_check_line(result: Plan) -> list[str]:
    """The derived reserve against the chosen route's own stretches, leg by leg."""
    from gcs_planner.mission.plan_json import reserve_of

    check = reserve_of(result).get("chosen_route")
    if not check:
        return []
    where = f"{check['from']} to {check['to']}"
    if check["covered"]:
        return [
            f"  the chosen route's stretches need at most {check['need_m']:,.0f} m ({where}: "
            "its turns, helices and gusts leg by leg): covered"
        ]
    return [
        f"warning: the chosen route's stretch {where} needs {check['need_m']:,.0f} m (its turns, "
        f"helices and gusts leg by leg), more than the reserve: --reserve "
        f"{math.ceil(check['need_m'])} states one that covers it"
    ]


def _design_hold(
    args: argparse.Namespace, scenario: Scenario, autopilot: str
) -> AltitudeHold | None:
    """``--turbulence`` (else the scenario's [environment] turbulence) through ``autopilot``'s
    altitude loop as shipped: the design the captures are given their vertical allowance for."""
    from gcs_planner.aircraft.altitude_hold import design_hold
    from gcs_planner.dryrun.air import flown_turbulence

    eas = scenario.envelope.eas if scenario.envelope is not None else scenario.cruise_airspeed
    return design_hold(flown_turbulence(args.turbulence, args.scenario), autopilot, eas)


def _capture_lines(result: Plan, c: dict | None = None) -> list[str]:
    from gcs_planner.mission.plan_json import capture_of

    c = capture_of(result) if c is None else c
    if c.get("turbulence"):
        t = c["turbulence"]
        worst = max((p["vertical_allowance_m"] for p in t["points"].values()), default=0.0)
        head = [f"turbulence: {t['describe']}; at most {worst:.2f} m"]
    else:
        head = []
    if c["warning"]:
        return [*head, f"warning: {c['warning']}"]
    if c["worst_point"] is None:
        return head
    return [
        *head,
        f"capture: every correction point fits its {c['capture_radius_m']:g} m capture radius "
        f"(worst {c['worst_point']}: {c['worst_need_m']:.2f} m of error on arrival, the worst over "
        f"the correction outcomes, and tracking allowance, {c['error_unit_m']:g} m per error unit)",
    ]


def _endurance_lines(result: Plan) -> list[str]:
    """The chosen route's flight time in the design wind, against the endurance if given."""
    from gcs_planner.core.flight_time import route_minutes

    minutes = route_minutes(result.scenario, result.route)
    text = f"flight time: {minutes:,.1f} min ({minutes / 60:.2f} h) in the design wind"
    endurance = result.scenario.endurance
    if endurance is not None:
        text += f", within the endurance of {endurance:g} min ({endurance - minutes:,.1f} left)"
    return [text]


def render(result: Plan, capture: dict | None = None) -> str:
    s = result.scenario
    p = s.params
    out = [
        f"scenario {s.name}: {s.n} points ({s.counts()['V']} V, {s.counts()['H']} H, "
        f"{s.counts()['unreliable']} unreliable)",
        f"parameters: alpha1={p.alpha1:g} alpha2={p.alpha2:g} beta1={p.beta1:g} "
        f"beta2={p.beta2:g} theta={p.theta:g} delta={p.delta:g} turn radius={p.turn_radius:g} m"
        + (
            f" p={p.p_success:g} r={p.fail_residual:g}"
            if "probability" in result.objectives
            else ""
        ),
        f"vehicle: {s.vehicle.describe()}",
        *(s.envelope.describe() if s.envelope is not None else ()),
        reserve_line(p.reserve, s.reserve_basis),
        *reserve_check_line(result),
        *(f"warning: {w}" for w in result.warnings),
        *_capture_lines(result, capture),
        *_endurance_lines(result),
        f"optimality: {result.statement}",
        "",
        f"Pareto front ({len(result.routes)} route{'' if len(result.routes) == 1 else 's'}; "
        f"* = chosen by {result.choice}"
        + (
            f" among routes with P >= {result.min_probability:g}"
            if result.min_probability > 0
            else ""
        )
        + (
            "; ? = not settled: routes with no more corrections or a higher probability may "
            "still be missing"
            if not all(result.proven())
            else ""
        )
        + "):",
        f"  {'':1} {'length m':>11} {'corr':>4} {'P arrive':>9} {'P lost':>7} {'gap m':>7}  route",
    ]
    certain, reliable = result.shortest_certain, result.most_reliable
    proven = result.proven()
    for i, (r, gap) in enumerate(zip(result.routes, result.gaps())):
        mark = "*" if i == result.chosen else " "
        ids = " ".join(r.ids())
        # "?" after the gap: not settled, routes with fewer corrections or a higher
        # probability may still be missing from the front (see core.proof).
        unsure = " " if proven[i] else "?"
        row = (
            f"{r.length:>11.1f} {r.corrections:>4} {r.probability:>9.4f} "
            f"{1 - r.probability:>7.4f} {gap:>7.1f}{unsure}"
        )
        out.append(f"  {mark} {row}  {ids}")
    if not result.threshold_met:
        out.append(
            f"  no route on this front arrives with P >= {result.min_probability:g}: the most "
            f"reliable one is chosen (lost with probability {1 - result.route.probability:.4f}); "
            "it is exported only with --allow-risky"
            + (
                ""
                if "probability" in result.objectives
                else "; --objectives length,corrections,probability may find likelier routes"
            )
        )
    if "probability" in result.objectives:
        out.append(
            "  shortest certain route: "
            + (
                f"{result.routes[certain].length:,.1f} m, {result.routes[certain].corrections} "
                "corrections"
                if certain is not None
                else "none on this front"
            )
            + f"; most reliable: P arrive {result.routes[reliable].probability:.4f} (lost "
            f"{1 - result.routes[reliable].probability:.4f}), "
            f"{result.routes[reliable].length:,.1f} m"
        )
    out += [
        "",
        f"chosen route ({result.route.corrections} corrections, "
        f"{result.route.length:,.1f} m, arrives with P {result.route.probability:.4f}, lost "
        f"with P {1 - result.route.probability:.4f}; errors on arrival before correction, "
        "margins to the point's limits; * unreliable point):",
        render_table(result.route),
    ]
    return "\n".join(out)


def _switch_time(args: argparse.Namespace) -> float:
    """--switch-time in seconds (only with --policy); the default when not given."""
    from gcs_planner.core.switch_room import DEFAULT_SWITCH_TIME_S
    from gcs_planner.errors import InputError

    if args.switch_time is None:
        return DEFAULT_SWITCH_TIME_S
    if not args.policy:
        raise InputError("only with --policy (the room to switch missions in)",
                         field="--switch-time")  # fmt: skip
    try:
        seconds = float(args.switch_time)
    except ValueError:
        seconds = math.nan
    if not (math.isfinite(seconds) and 0 <= seconds <= 600):
        raise InputError(
            f"must be a number of seconds in [0, 600], got {args.switch_time!r}",
            field="--switch-time",
        )
    return seconds


def _switch_room(scenario: Scenario, seconds: float) -> tuple[Scenario, SwitchRoom | None]:
    """The scenario with room to switch missions after every point (core/switch_room.py), and
    that room (None for straight legs, which have no run-outs)."""
    from gcs_planner.core.switch_room import applies, switch_room, with_switch_room

    if not applies(scenario):
        return scenario, None
    room = switch_room(scenario, seconds)
    return with_switch_room(scenario, room), room
