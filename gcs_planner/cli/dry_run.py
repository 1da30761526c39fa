"""`gcs-planner dry-run SCENARIO`: plan, export, upload to a mock vehicle on loopback, read back,
replay the stored mission, report (gcs_planner/dryrun/; the report's text:
gcs_planner/dryrun/render.py). The seldom-changed flags may stand in the scenario TOML's
``[dry_run]`` table (gcs_planner/dryrun/settings.py)."""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from typing import TYPE_CHECKING

from gcs_planner.aircraft.altitude_hold import design_hold
from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT
from gcs_planner.aircraft.derive import design_wind_speed
from gcs_planner.cli.common import (
    add_autopilot_argument,
    add_plan_arguments,
    add_scenario_arguments,
    load_scenario_from_args,
    plan_from_args,
)
from gcs_planner.cli.dry_run_policy import add_policy_arguments, refuse_plan_flags, run_policy
from gcs_planner.cli.vehicle_from import add_envelope_arguments, derive_envelope
from gcs_planner.core.capture import with_design_turbulence
from gcs_planner.core.choose import DEFAULT_MIN_PROBABILITY
from gcs_planner.dryrun.air import design_turbulence, flown_turbulence
from gcs_planner.dryrun.endurance import vehicle_endurance
from gcs_planner.dryrun.render import (
    SHOWN_ENVELOPE_SHORTFALLS,
    SHOWN_FLIGHT_LOSSES,
    render,
    safety_line,
    verdict_line,
)
from gcs_planner.dryrun.run import (
    DEVIATION_STEP_M,
    DRY_RUN_ACCEPTANCE_RADIUS_M,
    EXIT_LOST,
    EXIT_RISKY,
    DryRunReport,
    DryRunSettings,
    DryRunWorld,
    fly_dry_run,
)
from gcs_planner.dryrun.settings import read_dry_run_table
from gcs_planner.dryrun.track import write_track
from gcs_planner.errors import InputError, LinkError
from gcs_planner.link.protocol import DEFAULT_TIMEOUT_S
from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.plan_json import plan_to_dict
from gcs_planner.sim.live_vehicle import DEFAULT_TIME_SCALE
from gcs_planner.sim.replay import ReplayReport
from gcs_planner.sim.turbulence import Turbulence
from gcs_planner.sim.wind import WindSpec

if TYPE_CHECKING:
    from gcs_planner.aircraft.altitude_hold import AltitudeHold
    from gcs_planner.core.planner import Plan
    from gcs_planner.scenario.model import Scenario

# The report's text moved to gcs_planner/dryrun/render.py; its names stay importable here.
__all__ = [
    "SHOWN_ENVELOPE_SHORTFALLS",
    "SHOWN_FLIGHT_LOSSES",
    "add_parser",
    "flight_model_from_args",
    "parse_params",
    "parse_wind",
    "render",
    "run",
    "safety_line",
    "verdict_line",
]

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
    _add_vehicle_arguments(p)
    _add_air_arguments(p)
    _add_seldom_arguments(p)
    out = p.add_argument_group("the verdict and the output")
    out.add_argument(
        "--allow-risky",
        action="store_true",
        help="exit 0 even when the route arrives with a probability below --min-probability",
    )
    out.add_argument(
        "--track-out",
        metavar="PATH",
        help="write the flown track beside the mission's path (.geojson or .kml)",
    )
    out.add_argument("--json", action="store_true", help="print one JSON object, nothing else")
    add_policy_arguments(p.add_argument_group("a contingency policy instead of a plan"))
    # The flags a [dry_run] table may carry have no default of their own here: one not given
    # is the table's, else its default (_fill_from_table).
    p.set_defaults(func=run, min_probability=PlannersDefault(DEFAULT_MIN_PROBABILITY))
    p.set_defaults(time_scale=None)


def _add_vehicle_arguments(p: argparse.ArgumentParser) -> None:
    """The flown vehicle: its autopilot, its parameters, and what flies it."""
    g = p.add_argument_group("the flown vehicle")
    add_autopilot_argument(
        g,
        help=f"the autopilot the mock vehicle flies (default {DEFAULT_AUTOPILOT})",
        default=DEFAULT_AUTOPILOT,
    )
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
        "--set-params",
        action="store_true",
        help="deprecated: the plan's vehicle setup is now set by default (--vehicle-as-is "
        "flies without it)",
    )
    g.add_argument(
        "--endurance",
        metavar="MINUTES",
        help="the minutes of flight the aircraft has (default the scenario's [vehicle] "
        "endurance, else unlimited): a flight not at B by then is lost by the flight, as the "
        "low-battery failsafe ends the mission (ArduPlane BATT_FS_LOW_ACT, PX4 COM_LOW_BAT_ACT)",
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
        help="a JSBSim aircraft, the project's aerosonde or one the jsbsim package ships: what "
        "--flight-model jsbsim flies (default c172r); without it, the point mass flies and each "
        "leg is first checked against this aircraft's trims at its altitude (engine power, "
        "speed range, ceiling)",
    )


def _add_air_arguments(p: argparse.ArgumentParser) -> None:
    """The air flown and what the aircraft steers."""
    g = p.add_argument_group("the air flown")
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
        "--turbulence",
        metavar="SIGMA_W|LEVEL",
        help="vertical turbulence flown: the Dryden vertical gust of MIL-F-8785C, its standard "
        "deviation in m/s or a level of the standard (light, moderate, severe: sigma_w by "
        "altitude); default the scenario's [environment] turbulence, else none",
    )
    g.add_argument(
        "--design-turbulence",
        metavar="SIGMA_W|LEVEL",
        help="the vertical turbulence the plan's captures are given an allowance for (default: "
        "the turbulence flown; 0 flies a plan made for still air in --turbulence)",
    )
    g.add_argument(
        "--navigate-on-truth",
        action="store_true",
        help="the aircraft flies its true position instead of its INS estimate (comparison)",
    )


def _add_seldom_arguments(p: argparse.ArgumentParser) -> None:
    """The runs and the link: seldom changed, so the scenario's [dry_run] table may set them
    (gcs_planner/dryrun/settings.py) and a flag given wins. No defaults here (see
    :data:`TABLE_DEFAULTS`)."""
    g = p.add_argument_group(
        "the runs and the link",
        "Seldom changed: the scenario TOML's [dry_run] table may set these, --min-probability "
        "and --time-scale, each under its flag's name with underscores (runs = 200, "
        "min_probability = 0.95); a flag given wins.",
    )
    g.add_argument(
        "--runs",
        metavar="N",
        help="flights for the verdict, each with its own draws (default 0: one seeded flight, "
        "a demonstration)",
    )
    g.add_argument(
        "--seed", metavar="S", help="seeds the losses and the replay's draws (default 0)"
    )
    g.add_argument(
        "--loss",
        metavar="RATE",
        help="fraction of MAVLink messages the vehicle drops, both ways, seeded (default 0)",
    )
    g.add_argument(
        "--timeout",
        metavar="SECONDS",
        help=f"ground station's wait per message (default {DEFAULT_TIMEOUT_S:g})",
    )
    g.add_argument(
        "--acceptance-radius",
        metavar="M",
        help="waypoint ACCEPTANCE radius exported and set on the vehicle, whole metres 1..255 "
        f"(default {DRY_RUN_ACCEPTANCE_RADIUS_M}: the autopilot flies up to each point)",
    )


class PlannersDefault(float):
    """--min-probability not given: the planner's default, which a [dry_run] table may change.
    A number still, so that the flags parsed alone plan as before."""


# The default of each flag a [dry_run] table may set, as the flag's own text, when neither the
# command line nor the table gives it (--min-probability: its own default, PlannersDefault).
TABLE_DEFAULTS: dict[str, str] = {
    "runs": "0",
    "seed": "0",
    "loss": "0",
    "timeout": str(DEFAULT_TIMEOUT_S),
    "acceptance_radius": str(DRY_RUN_ACCEPTANCE_RADIUS_M),
    "time_scale": str(DEFAULT_TIME_SCALE),
}


def _fill_from_table(args: argparse.Namespace) -> None:
    """Each flag the scenario's [dry_run] table may set and the command line left unset: the
    table's value, else the flag's default. Bad keys or values in the table are InputError
    naming the file and the key."""
    table = read_dry_run_table(args.scenario)
    for name, default in TABLE_DEFAULTS.items():
        if getattr(args, name, None) is None:  # a flag given wins
            setattr(args, name, str(table[name]) if name in table else default)
    if isinstance(args.min_probability, PlannersDefault):
        args.min_probability = float(table.get("min_probability", args.min_probability))


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
    from gcs_planner.sim.jsbsim_airframe import (
        DEFAULT_AIRCRAFT,
        CheckedPointMass,
        FlightModel,
        available_aircraft,
    )

    name = args.aircraft or DEFAULT_AIRCRAFT
    shipped = available_aircraft()
    if name not in shipped:
        light = ", ".join(("aerosonde", "c172r", "c172x", "c182", "c310", "J3Cub", "pa28"))
        raise InputError(
            f"no JSBSim aircraft {name!r} (shipped: {len(shipped)}, e.g. {light})",
            field="--aircraft",
        )
    if args.flight_model != "jsbsim":
        return CheckedPointMass(FlightModel(name))
    return FlightModel(name)


def run(args: argparse.Namespace) -> int:
    _fill_from_table(args)
    if args.policy is not None:
        for flag, given in (
            ("--turbulence", args.turbulence),
            ("--design-turbulence", args.design_turbulence),
            ("--endurance", args.endurance),
        ):
            if given is not None:
                raise InputError(f"the policy dry run does not take {flag}", field=flag)
        if args.flight_model != "point-mass" or args.aircraft is not None:
            raise InputError("the policy dry run flies the point mass only", field="--flight-model")
        refuse_plan_flags(args)
        return run_policy(args, _number, parse_params(args.param))
    if args.onboard:
        raise InputError("only with --policy (a policy switched on board)", field="--onboard")
    if args.set_params:
        print(
            "gcs-planner: note: --set-params is deprecated: the plan's vehicle setup is set by "
            "default (--vehicle-as-is flies without it)",
            file=sys.stderr,
        )
    runs = int(_number(args.runs, "--runs", int, 0))
    wind = parse_wind(args.wind, args.gust)
    wind = replace(wind, turbulence=flown_turbulence(args.turbulence, args.scenario))
    designed = design_turbulence(args.design_turbulence, wind.turbulence)
    endurance = vehicle_endurance(args.endurance, args.scenario)
    params = parse_params(args.param)
    settings = _settings(args, runs)
    model = flight_model_from_args(args)
    track_out = args.track_out
    if track_out is not None and not track_out.lower().endswith((".geojson", ".json", ".kml")):
        raise InputError("must end in .geojson, .json or .kml", field="--track-out")
    scenario = load_scenario_from_args(args)
    if args.aircraft is not None:  # the plan flown climbs within the airframe (issue 52)
        from gcs_planner.aircraft.airframe_trim import bound_by_airframe

        scenario = bound_by_airframe(args, scenario)
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
        flown_by=args.autopilot,
        # The gusts flown are the plan's design gusts: the derived reserve covers them.
        gust=wind.gust,
    )
    # The plan keeps to the endurance the flights are judged against (core/endurance_front.py).
    scenario = replace(scenario, endurance=endurance)
    hold = _design_hold(args, scenario, designed, params)
    if hold is not None:  # each capture's vertical allowance, kept to in the search
        scenario = with_design_turbulence(scenario, hold)
    result = plan_from_args(args, scenario)
    _check_design_turbulence(args, result, hold)
    # The vehicle's landmark database comes from the file again, not from the planner.
    world = DryRunWorld(
        result,
        load_scenario_from_args(args),
        flavour=args.autopilot,
        wind=wind,
        endurance=endurance,
        design_wind=design_wind_speed(argparse.Namespace(wind=design), scenario),
        navigate_on_estimate=not args.navigate_on_truth,
        flight_model=model,
        set_params=params,
        vehicle_as_is=args.vehicle_as_is,
    )
    flown: list = []
    report = fly_dry_run(world, settings, track=flown)
    if track_out is not None and flown:
        _write_track(track_out, flown[0], world)
    return _report(args, report, result.min_probability)


def _design_hold(
    args: argparse.Namespace,
    scenario: Scenario,
    designed: Turbulence | None,
    params: dict[str, float],
) -> AltitudeHold | None:
    """The plan made for the ``designed`` turbulence through the flown autopilot's altitude
    loop, at its --param value, else as shipped (None: no turbulence designed for)."""
    eas = scenario.envelope.eas if scenario.envelope is not None else scenario.cruise_airspeed
    return design_hold(designed, args.autopilot or DEFAULT_AUTOPILOT, eas, params)


def _check_design_turbulence(
    args: argparse.Namespace, result: Plan, hold: AltitudeHold | None
) -> None:
    """The chosen route's captures in the design turbulence, checked again as the plan checks
    them (the search keeps to them; a route found past its budget may not): one that does not
    fit is not flown unless --allow-risky."""
    if hold is None:
        return
    from gcs_planner.aircraft.profile import TRACKING_ALLOWANCE_M
    from gcs_planner.core.capture import turbulence_capture

    check = turbulence_capture(result.route.stops, result.scenario, TRACKING_ALLOWANCE_M, hold)
    planned = f"planned for {hold.describe()}"
    if check["warning"] is None:
        print(f"gcs-planner: note: {planned}: every capture fits", file=sys.stderr)
        return
    if not args.allow_risky:
        from gcs_planner.core.choose import RiskyRouteError

        raise RiskyRouteError(f"{planned}: {check['warning']}; not flown: pass --allow-risky")
    print(f"gcs-planner: warning: {planned}: {check['warning']}", file=sys.stderr)


def _settings(args: argparse.Namespace, runs: int) -> DryRunSettings:
    """``runs`` and the link of the flags (or the [dry_run] table), checked: one line, exit 2
    when bad."""
    return DryRunSettings(
        runs=runs,
        loss=_number(args.loss, "--loss", float, 0.0, 1.0),
        seed=int(_number(args.seed, "--seed", int, 0)),
        timeout=_number(args.timeout, "--timeout", float, 1e-3),
        acceptance_radius=int(_number(args.acceptance_radius, "--acceptance-radius", int, 1, 256)),
    )


def _write_track(path: str, replayed: ReplayReport, world: DryRunWorld) -> None:
    """--track-out: the flown track beside the mission's path; InputError naming the flag when
    it cannot be written."""
    try:
        planned = trajectory_local(plan_to_dict(world.plan), step=DEVIATION_STEP_M)
        write_track(path, replayed, world.landmarks, world.plan.route.ids(), planned)
    except OSError as exc:
        message = f"cannot write {path}: {exc.strerror}"
        raise InputError(message, field="--track-out") from None
    except InputError as exc:  # write_atomic's own words, named by the flag
        if exc.field is None:
            raise InputError(exc.reason, file=exc.file, field="--track-out") from None
        raise


def _report(args: argparse.Namespace, report: DryRunReport, floor: float) -> int:
    """Print the report (text or --json) and the verdict's line; the exit code."""
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
