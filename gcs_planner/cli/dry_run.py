"""`gcs-planner dry-run SCENARIO`: plan, export, upload to a mock vehicle on loopback, read back,
replay the stored mission, report."""

from __future__ import annotations

import argparse
import json
import sys

from gcs_planner.aircraft.derive import design_wind_speed
from gcs_planner.cli.common import (
    add_plan_arguments,
    add_scenario_arguments,
    load_scenario_from_args,
    plan_from_args,
)
from gcs_planner.cli.dry_run_policy import add_policy_arguments, refuse_plan_flags, run_policy
from gcs_planner.cli.vehicle_from import add_envelope_arguments, derive_envelope
from gcs_planner.dryrun.run import (
    DEVIATION_STEP_M,
    DRY_RUN_ACCEPTANCE_RADIUS_M,
    EXIT_LOST,
    EXIT_RISKY,
    DryRunReport,
    LostRunRow,
    dry_run,
)
from gcs_planner.dryrun.track import write_track
from gcs_planner.errors import InputError, LinkError
from gcs_planner.aircraft.profile import FIRMWARES
from gcs_planner.link.protocol import DEFAULT_TIMEOUT_S
from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.plan_json import plan_to_dict
from sim.replay import CHORD_SHORTFALL, QUANTISATION_M
from sim.wind import WindSpec

# Runs lost by the flight named one by one in the text report (all of them in --json).
SHOWN_FLIGHT_LOSSES = 5
# Legs outside the envelope in the wind flown named one by one (all of them in --json).
SHOWN_ENVELOPE_SHORTFALLS = 8

EPILOG = f"""exit codes: 0 the mission verified and, with --runs N, no run was lost by the flight
and the success rate is consistent with the planned probability (without --runs: the one seeded
flight, a demonstration, arrived) and the route arrives with at least --min-probability (or
--allow-risky); 2 bad input; 3 no feasible route, or a route below --min-probability;
{LinkError.exit_code} the
upload failed or the read-back differs; {EXIT_LOST} the mission verified but the verdict failed:
a run lost by the flight, a success rate not consistent with the plan, a mission the airframe cannot
fly, or legs that do not fit the aircraft's envelope in the wind flown (the output says where
and which limit)."""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "dry-run",
        help="plan, upload to a mock vehicle over loopback, read back, replay and report",
        description="Plan the scenario, export the chosen route, upload it with the project's "
        "MAVLink client to a mock vehicle on 127.0.0.1 (its landmarks: the scenario, loaded on "
        "its own), read it back and compare, then replay the mission the vehicle stored with "
        "INS drift and corrections.",
        epilog=EPILOG,
    )
    add_scenario_arguments(p)
    add_plan_arguments(p)
    add_envelope_arguments(p, wind=False, autopilot=False)
    g = p.add_argument_group("dry run")
    g.add_argument("--firmware", choices=FIRMWARES, default="ardupilot", help="vehicle flavour")
    g.add_argument(
        "--runs",
        default="0",
        metavar="N",
        help="flights for the verdict, each with its own draws (default 0: one seeded flight, "
        "a demonstration)",
    )
    g.add_argument(
        "--wind",
        default="0",
        metavar="SPEED[@FROM_DEG]",
        help="steady wind flown, m/s, from FROM_DEG (clockwise from north; default: a "
        "direction drawn per flight); also the plan's design wind unless --design-wind",
    )
    g.add_argument(
        "--design-wind",
        metavar="SPEED[@FROM_DEG]",
        help="the wind the plan's envelope must hold in (default: the wind flown; 0 flies a "
        "still-air plan in --wind); --turn-radius and the angles given directly win",
    )
    g.add_argument("--gust", default="0", metavar="SPEED", help="gusts, m/s per axis (default 0)")
    g.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="set an autopilot parameter on the vehicle after the upload (repeatable), e.g. "
        "TECS_CLMB_MAX=8 or NAVL1_LIM_BANK=45",
    )
    g.add_argument(
        "--vehicle-as-is",
        action="store_true",
        help="fly the vehicle at its own parameters, without the plan's vehicle setup (what an "
        "unprepared aircraft does); by default the setup plan --out writes is set with the "
        "mission, as the operator loads it",
    )
    g.add_argument(
        "--allow-risky",
        action="store_true",
        help="exit 0 even when the route arrives with a probability below --min-probability",
    )
    g.add_argument(
        "--set-params",
        action="store_true",
        help="deprecated: the plan's vehicle setup is now set by default (--vehicle-as-is "
        "flies without it)",
    )
    g.add_argument(
        "--navigate-on-truth",
        action="store_true",
        help="the aircraft flies its true position instead of its INS estimate (comparison)",
    )
    g.add_argument(
        "--loss",
        default="0",
        metavar="RATE",
        help="fraction of MAVLink messages the vehicle drops, both ways, seeded (default 0)",
    )
    g.add_argument(
        "--seed", default="0", metavar="S", help="seeds the losses and the replay's draws"
    )
    g.add_argument(
        "--timeout",
        default=str(DEFAULT_TIMEOUT_S),
        metavar="SECONDS",
        help=f"ground station's wait per message (default {DEFAULT_TIMEOUT_S:g})",
    )
    g.add_argument(
        "--acceptance-radius",
        default=str(DRY_RUN_ACCEPTANCE_RADIUS_M),
        metavar="M",
        help="waypoint ACCEPTANCE radius exported and set on the vehicle, whole metres 1..255 "
        f"(default {DRY_RUN_ACCEPTANCE_RADIUS_M}: the autopilot flies up to each point)",
    )
    g.add_argument(
        "--track-out",
        metavar="PATH",
        help="write the flown track beside the mission's path (.geojson or .kml)",
    )
    g.add_argument(
        "--flight-model",
        choices=("point-mass", "jsbsim"),
        default="point-mass",
        help="what flies the autopilot's demands: the point mass (default) or JSBSim's flight "
        "dynamics (the jsbsim extra: pip install '.[jsbsim]'; docs/jsbsim.md)",
    )
    g.add_argument(
        "--aircraft",
        metavar="NAME",
        help="a JSBSim aircraft, one shipped with the jsbsim package: what --flight-model jsbsim "
        "flies (default c172r); without it, the point mass flies and each leg is first checked "
        "against this aircraft's trims at its altitude (engine power, speed range, ceiling)",
    )
    g.add_argument("--json", action="store_true", help="print one JSON object, nothing else")
    add_policy_arguments(g)
    p.set_defaults(func=run)


def _number(text: str, flag: str, kind: type, low: float, high: float | None = None) -> float:
    """A flag's value checked here, not by argparse, so a bad one is one line and exit 2."""
    try:
        value = kind(text)
    except ValueError:
        raise InputError(f"not a number: {text!r}", field=flag) from None
    if not (value >= low and (high is None or value < high)):
        bound = f">= {low:g}" if high is None else f"in [{low:g}, {high:g})"
        raise InputError(f"must be {bound}, got {text!r}", field=flag)
    return value


def parse_wind(text: str, gust_text: str) -> WindSpec:
    """``SPEED[@FROM_DEG]`` and the gust speed, checked here (one line, exit 2 when bad)."""
    speed_text, _, direction_text = text.partition("@")
    speed = _number(speed_text, "--wind", float, 0.0, 100.0)
    direction = None
    if direction_text:
        direction = _number(direction_text, "--wind", float, 0.0, 360.0)
    gust = _number(gust_text, "--gust", float, 0.0, 50.0)
    return WindSpec(speed, direction, gust)


def parse_params(pairs: list[str]) -> dict[str, float]:
    """``NAME=VALUE`` pairs (one line, exit 2 when bad)."""
    out: dict[str, float] = {}
    for pair in pairs:
        name, sep, value = pair.partition("=")
        if not sep or not name or len(name) > 16:
            raise InputError(f"expected NAME=VALUE (a name of 1-16 characters), got {pair!r}",
                             field="--param")  # fmt: skip
        out[name] = _number(value, "--param", float, -1e9, 1e9)
    return out


def flight_model_from_args(args: argparse.Namespace) -> object | None:
    """The flight model of the flags, checked here: JSBSim's with --flight-model jsbsim; the
    point mass checked against a JSBSim aircraft with --aircraft alone; None (the point mass)
    with neither. The extra installed, the aircraft one that jsbsim ships (one line, exit 2
    when not)."""
    if args.flight_model != "jsbsim" and args.aircraft is None:
        return None
    flag = "--flight-model" if args.flight_model == "jsbsim" else "--aircraft"
    try:
        import jsbsim  # noqa: F401
    except ImportError:
        raise InputError("needs the jsbsim package: pip install '.[jsbsim]'", field=flag) from None
    from sim.jsbsim_airframe import (
        DEFAULT_AIRCRAFT,
        CheckedPointMass,
        FlightModel,
        available_aircraft,
    )

    name = args.aircraft or DEFAULT_AIRCRAFT
    shipped = available_aircraft()
    if name not in shipped:
        light = ", ".join(a for a in ("c172r", "c172x", "c182", "c310", "J3Cub", "pa28"))
        raise InputError(
            f"no JSBSim aircraft {name!r} (shipped: {len(shipped)}, e.g. {light})",
            field="--aircraft",
        )
    if args.flight_model != "jsbsim":
        return CheckedPointMass(FlightModel(name))
    return FlightModel(name)


def run(args: argparse.Namespace) -> int:
    if args.policy is not None:
        if args.flight_model != "point-mass" or args.aircraft is not None:
            raise InputError("the policy dry run flies the point mass only", field="--flight-model")
        refuse_plan_flags(args)
        return run_policy(args, _number, parse_params(args.param))
    if args.set_params:
        print(
            "gcs-planner: note: --set-params is deprecated: the plan's vehicle setup is set by "
            "default (--vehicle-as-is flies without it)",
            file=sys.stderr,
        )
    runs = int(_number(args.runs, "--runs", int, 0))
    wind = parse_wind(args.wind, args.gust)
    settings = parse_params(args.param)
    loss = _number(args.loss, "--loss", float, 0.0, 1.0)
    seed = int(_number(args.seed, "--seed", int, 0))
    timeout = _number(args.timeout, "--timeout", float, 1e-3)
    acceptance = int(_number(args.acceptance_radius, "--acceptance-radius", int, 1, 256))
    model = flight_model_from_args(args)
    track_out = args.track_out
    if track_out is not None and not track_out.lower().endswith((".geojson", ".json", ".kml")):
        raise InputError("must end in .geojson, .json or .kml", field="--track-out")
    scenario = load_scenario_from_args(args)
    # The wind flown, unless --design-wind; a still flight (the default "0") leaves the
    # scenario file's [environment] wind, if any, as the design wind.
    design = args.design_wind if args.design_wind is not None else args.wind
    if args.design_wind is None and parse_wind(args.wind, "0").still:
        design = None
    scenario = derive_envelope(
        args,
        scenario,
        wind_text=design,
        wind_field="--design-wind" if args.design_wind is not None else "--wind",
        # The flown autopilot's defaults fill only what a rate or bank flag leaves open: a dry
        # run with none plans with the stated (or assumed) envelope, as before.
        autopilot_defaults=False,
        # ... but the legs run straight over each landmark as far as the flown autopilot needs.
        flown_by=args.firmware,
        # The gusts flown are the plan's design gusts: the derived reserve covers them.
        gust=wind.gust,
    )
    result = plan_from_args(args, scenario)
    # The vehicle's landmark database comes from the file again, not from the planner.
    landmarks = load_scenario_from_args(args)
    flown: list = []
    report = dry_run(
        result,
        landmarks,
        flavour=args.firmware,
        runs=runs,
        loss=loss,
        seed=seed,
        timeout=timeout,
        acceptance_radius=acceptance,
        track=flown,
        wind=wind,
        navigate_on_estimate=not args.navigate_on_truth,
        set_params=settings,
        vehicle_as_is=args.vehicle_as_is,
        flight_model=model,
        design_wind=design_wind_speed(argparse.Namespace(wind=design), scenario),
    )
    if track_out is not None and flown:
        try:
            planned = trajectory_local(plan_to_dict(result), step=DEVIATION_STEP_M)
            write_track(track_out, flown[0], landmarks, result.route.ids(), planned)
        except OSError as exc:
            message = f"cannot write {track_out}: {exc.strerror}"
            raise InputError(message, field="--track-out") from None
        except InputError as exc:  # write_atomic's own words, named by the flag
            if exc.field is None:
                raise InputError(exc.reason, file=exc.file, field="--track-out") from None
            raise
    floor = result.min_probability
    risky = report.planned_probability < floor and not args.allow_risky
    if args.json:
        out = report.to_dict()
        out["min_probability"] = floor
        out["verdict"] = safety_line(report, floor, args.allow_risky)
        sys.stdout.write(json.dumps(out, indent=2) + "\n")
    else:
        print(render(report))
        print(safety_line(report, floor, args.allow_risky))
    if not report.verified:
        print(f"gcs-planner: error: {report.link_error}", file=sys.stderr)
        return LinkError.exit_code
    if not report.ok:
        print(f"gcs-planner: {verdict_line(report)}", file=sys.stderr)
        return EXIT_LOST
    if risky:
        print(
            f"gcs-planner: the route arrives with P {report.planned_probability:.4f}, below "
            f"--min-probability {floor:g}: pass --allow-risky to accept it",
            file=sys.stderr,
        )
        return EXIT_RISKY
    return 0


def safety_line(r: DryRunReport, floor: float, allow_risky: bool) -> str:
    """The verdict an operator acts on, in one line: verified, flown, and the route's arrival
    probability against the planner's threshold."""
    if not r.verified:
        return "VERDICT: NOT VERIFIED: the upload failed; nothing flew"
    flown = "flown: " + ("OK" if r.ok else "FAILED (" + verdict_line(r) + ")")
    if r.demonstration:
        flown += " (one seeded flight: a demonstration, --runs N for a verdict)"
    p = r.planned_probability
    if p >= floor:
        odds = f"arrives with P {p:.4f} >= {floor:g} (--min-probability)"
    elif allow_risky:
        odds = f"RISKY: arrives with P {p:.4f} < {floor:g} (--min-probability), accepted by "
        odds += "--allow-risky"
    else:
        odds = f"RISKY: arrives with P {p:.4f} < {floor:g} (--min-probability)"
    good = r.ok and (p >= floor or allow_risky) and not r.demonstration
    head = "VERDICT: GO" if good else "VERDICT: NO GO"
    if r.ok and r.demonstration and (p >= floor or allow_risky):
        head = "VERDICT: DEMONSTRATION ONLY"
    return f"{head}: verified; {flown}; {odds}"


def verdict_line(r: DryRunReport) -> str:
    """Why the verdict failed, in one line."""
    if r.airframe_limits:
        return r.why
    parts = []
    if r.envelope_shortfalls:
        first = r.envelope_shortfalls[0]
        legs = len({s.leg for s in r.envelope_shortfalls})
        parts.append(
            f"{legs} leg(s) do not fit the aircraft's envelope in the {r.envelope_wind:g} m/s wind "
            f"flown (first: {first.describe()})"
        )
    if r.runs == 0:
        if not r.arrived:
            parts.append(f"lost: {r.why}")
            if r.setup_shortfalls:
                parts.append(_first_cause(r))
        return "; ".join(parts)
    if r.flight_losses:
        parts.append(f"{r.flight_losses} of {r.runs} runs lost by the flight")
    if (r.flight_losses or r.missed) and r.setup_shortfalls:
        parts.append(_first_cause(r))
    if not r.probability_within_ci:
        parts.append("the success rate is not consistent with the planned probability")
    return "verdict failed: " + "; ".join(parts or ["see the report"])


def _first_cause(r: DryRunReport) -> str:
    """What the vehicle was not set up for, first of all (the setup's order: airspeed, then
    climb and sink, roll, loiters)."""
    return "first cause: the vehicle is not set up for the plan: " + r.setup_shortfalls[0]


def render(r: DryRunReport) -> str:
    corrections = len(r.route) - 2
    out = [
        f"dry run of {r.scenario} on a mock {r.flavour} vehicle over UDP 127.0.0.1 "
        f"(loss {r.loss:g}, seed {r.seed})",
        f"route: {' '.join(r.route)} ({corrections} corrections, planned "
        f"{r.planned_length:,.1f} m, planned probability {r.planned_probability:.4f})",
    ]
    if r.verified:
        out.append(
            f"upload: {r.items} items, read back and equal (verified) in {r.upload_seconds:.2f} s"
            f", {r.resends} resends, {r.messages_dropped} messages dropped"
        )
    else:
        out.append(f"upload: NOT verified after {r.upload_attempts} attempt(s): {r.link_error}")
    for n, error in enumerate(r.upload_errors[: r.upload_attempts - 1 if r.verified else -1], 1):
        out.append(f"  attempt {n} failed: {error}")
    if not r.verified:
        return "\n".join(out)  # nothing flew: nothing more to say
    if r.vehicle_as_is:
        out.append("setup: none set: the vehicle flies at its own parameters (--vehicle-as-is)")
    elif r.setup:
        out.append(
            f"setup: the plan's vehicle setup set with the mission ({len(r.setup)} parameters: "
            + ", ".join(r.setup)
            + ")"
        )
    for short in r.setup_shortfalls:
        out.append(f"  NOT SET UP: {short}")
    out += ["", _table(r), ""]
    within = "within" if r.length_within_tolerance else "OUTSIDE"
    if r.length_within_tolerance is None:
        within = f"not measured ({r.helices} helices: the chords skip them) against"
    out.append(
        f"length: the stored mission flies {r.mission_length:,.1f} m from A to B, planned "
        f"{r.planned_length:,.1f} m: difference {r.length_difference:+.2f} m, {within} the "
        f"tolerance {r.length_tolerance:.2f} m ({CHORD_SHORTFALL:.3%} of {r.arc_length:,.1f} m "
        f"of arcs + {QUANTISATION_M * 100:g} cm x {r.waypoints} waypoints)"
    )
    out.append(
        f"flight: {r.flavour} mode AUTO with the scenario's vehicle profile flies "
        f"{r.flown_to_b:,.1f} m to B in {r.flight_seconds / 60:.1f} min, planned "
        f"{r.planned_length:,.1f} m: difference {r.flown_difference:+.1f} m; largest deviation "
        f"from the planned path {r.max_deviation:.1f} m (3D), {r.max_deviation_at:,.0f} m from "
        f"A; acceptance radius {r.acceptance_radius:g} m, capture radius {r.capture_radius:g} m"
    )
    if r.max_overrun is not None:
        covered = (
            "within the plan's flight reserve"
            if r.max_overrun <= r.reserve
            else "MORE than the plan's flight reserve"
        )
        out.append(
            f"overrun: at most {r.max_overrun:+,.1f} m flown beyond the plan between two "
            f"corrections of an error, {covered} of {r.reserve:,.0f} m"
        )
    for note in r.flight_notes:
        out.append(f"  note: {note}")
    if r.flight_model != "point mass":
        out.append(f"flight model: {r.flight_model}")
    else:
        # What the point mass cannot tell (docs/jsbsim.md, the cross-check's disagreements).
        out.append(
            "flight model: point mass (rolls into its turns; climbs and sinks at the autopilot's "
            "rates at once, at any altitude: no engine power, ceiling or speed-height coupling; "
            "--flight-model jsbsim flies an airframe)"
        )
    for limit in r.airframe_limits:
        out.append(f"  CANNOT FLY: {limit}")
    for shortfall in r.airframe_shortfalls:
        out.append(f"  could not hold: {shortfall}")
    out += _envelope_lines(r)
    if r.missed:
        out.append(
            "missed: "
            + ", ".join(f"{m.kind} {m.point} by {m.miss:.1f} m" for m in r.missed)
            + f" (outside the {r.capture_radius:g} m capture radius: no correction)"
        )
    if not r.arrived:
        out.append(f"flown {r.flown_length:,.1f} m before the vehicle was lost")
    if not r.corrections_as_planned:
        out.append("corrections: NOT the planned points in the planned order (see the rows)")
    out.append(
        f"world: {r.wind}; autopilot {r.autopilot}; the aircraft steers its "
        + ("INS estimate (corrections where the true track passes within the capture radius)"
           if r.navigate_on_estimate else "true position")
    )  # fmt: skip
    for assumption in r.assumptions:
        out.append(f"  assumed: {assumption}")
    if r.runs > 0 and r.success_rate is not None and r.success_ci is not None:
        low, high = r.success_ci
        if r.reserve > 0:  # the plan's probability is a floor: held to limits less the reserve
            verdict = "kept" if r.probability_within_ci else "NOT kept (above the interval)"
            said = f"planned at least {r.planned_probability:.4f} (with the reserve): {verdict}"
        else:
            verdict = "within" if r.probability_within_ci else "OUTSIDE"
            said = f"planned probability {r.planned_probability:.4f}: {verdict} the interval"
        how = "flights, each with its own draws" if r.runs_flown else "replays of one flight"
        out.append(
            f"success rate {r.success_rate:.3f} over {r.runs} {how} "
            f"({(r.confidence or 0) * 100:g} % Wilson interval {low:.3f}-{high:.3f}); {said}"
        )
        out.append(
            f"losses: {r.flight_losses} by the flight (a missed landmark, or lost where the plan "
            "flown as planned with the same correction outcomes arrives), "
            f"{r.correction_losses} by failed corrections"
        )
        flight = [lost for lost in r.lost_runs if lost.by_the_flight]
        for lost in flight[:SHOWN_FLIGHT_LOSSES]:
            out.append(f"  run {lost.run} lost by the flight: {_lost_run(lost)}")
        if len(flight) > SHOWN_FLIGHT_LOSSES:
            out.append(f"  ... {len(flight) - SHOWN_FLIGHT_LOSSES} more (lost_runs in --json)")
    if r.planned_probability < 1.0:
        out.append(
            f"note: the planned probability is {r.planned_probability:.4f} < 1: this replay is "
            f"one seeded draw (--seed {r.seed})"
            + ("" if r.runs else "; --runs N gives the success rate")
        )
    if r.demonstration:
        out.append(
            "note: one seeded flight is a demonstration, not a verdict: --runs N flies N, each "
            "with its own draws"
        )
    if not r.verified:
        out.append("result: the upload did not verify")
    elif r.airframe_limits:
        out.append(f"result: the mission cannot be flown: {r.why}")
    elif r.envelope_shortfalls:
        out.append("result: NOT verified: " + verdict_line(r).removeprefix("verdict failed: "))
    elif r.demonstration:
        out.append("result: verified and arrived" if r.arrived else f"result: LOST: {r.why}")
    elif r.ok:
        out.append(
            f"result: verified; no run lost by the flight; success rate consistent with the "
            f"planned probability (this draw: {'arrived' if r.arrived else 'lost'})"
        )
    else:
        out.append(f"result: NOT verified by the flight: {verdict_line(r)}")
    return "\n".join(out)


def _envelope_lines(r: DryRunReport) -> list[str]:
    """The plan's legs against its aircraft's envelope in the wind flown (checked before the
    flight): a summary per limit, then the shortfalls one by one."""
    if r.envelope_wind is None:
        return []
    where = (
        "from any direction" if r.envelope_wind_from is None
        else f"from {r.envelope_wind_from:g} deg, climbs along each leg's track"
    )  # fmt: skip
    head = f"envelope in the wind flown ({r.envelope_wind:g} m/s {where}, per leg at "
    head += "the TAS of its highest point): "
    if not r.envelope_shortfalls:
        return [head + "every leg fits"]
    by_limit: dict[str, list] = {}
    for s in r.envelope_shortfalls:
        by_limit.setdefault(s.limit, []).append(s)
    summary = []
    for limit, rows in by_limit.items():
        worst = max(rows, key=lambda s: abs(s.needs - s.can))
        summary.append(
            f"{limit} on {len(rows)} leg(s) (worst leg {worst.leg}: planned {worst.needs:.2f} "
            f"{worst.unit}, in this wind {worst.can:.2f} {worst.unit})"
        )
    out = [head + "DOES NOT FIT: " + "; ".join(summary)]
    for s in r.envelope_shortfalls[:SHOWN_ENVELOPE_SHORTFALLS]:
        out.append(f"  DOES NOT FIT: {s.describe()}")
    more = len(r.envelope_shortfalls) - SHOWN_ENVELOPE_SHORTFALLS
    if more > 0:
        out.append(f"  ... {more} more (envelope_shortfalls in --json)")
    return out


def _lost_run(lost: LostRunRow) -> str:
    parts = [lost.reason or "lost"]
    if lost.missed:
        parts.append("missed " + ", ".join(lost.missed))
    if lost.failed:
        parts.append("failed corrections at " + ", ".join(lost.failed))
    return "; ".join(parts)


def _table(r: DryRunReport) -> str:
    head = (
        f"{'point':>6} {'kind':>4} {'flown m':>10} {'v err':>7} {'h err':>7} "
        f"{'v margin':>8} {'h margin':>8} {'planned v':>9} {'planned h':>9}  outcome"
    )
    lines = [head]
    for row in r.rows:
        kind = row.kind + ("*" if row.unreliable else "")
        if row.outcome == "missed":
            lines.append(
                f"{row.point:>6} {kind:>4} {row.distance:>10.1f} {'-':>7} {'-':>7} {'-':>8} "
                f"{'-':>8} {'-':>9} {'-':>9}  MISSED by {row.miss:.1f} m (3D)"
            )
            continue
        pv = "-" if row.planned_v is None else f"{row.planned_v:.3f}"
        ph = "-" if row.planned_h is None else f"{row.planned_h:.3f}"
        outcome = row.outcome + ("" if row.on_route else " (not on route)")
        lines.append(
            f"{row.point:>6} {kind:>4} {row.distance:>10.1f} {row.v_before:>7.3f} "
            f"{row.h_before:>7.3f} {row.v_margin:>8.3f} {row.h_margin:>8.3f} {pv:>9} {ph:>9}"
            f"  {outcome}"
        )
    if r.arrived or not any(row.outcome == "lost" for row in r.rows):
        b = r.route[-1]
        lines.append(
            f"{b:>6} {'B':>4} {r.flown_length:>10.1f} {r.v_at_b:>7.3f} {r.h_at_b:>7.3f} "
            f"{r.theta - r.v_at_b:>8.3f} {r.theta - r.h_at_b:>8.3f} {'':>9} {'':>9}  "
            + ("arrived" if r.arrived else "lost")
        )
    lines.append("* unreliable point; errors on arrival, before the correction")
    return "\n".join(lines)
