"""Arguments shared by the commands that read a scenario (plan, mock-vehicle, dry-run) and by
the commands that plan one (plan, dry-run)."""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from gcs_planner.aircraft.autopilot import AUTOPILOTS
from gcs_planner.aircraft.profile import LEG_MODELS
from gcs_planner.core.budget import DEFAULT_TIME_LIMIT
from gcs_planner.core.choose import DEFAULT_MIN_PROBABILITY
from gcs_planner.errors import InputError
from gcs_planner.runtime.progress import on_terminal

if TYPE_CHECKING:
    from gcs_planner.core.planner import Plan
    from gcs_planner.scenario.model import Scenario

# The route choices (gcs_planner.core.choose.CHOICES, not imported: it pulls numpy in).
CHOICES = ("compromise", "shortest", "fewest", "most-reliable")
# The objectives (gcs_planner.core.planner.OBJECTIVES, not imported for the same reason).
OBJECTIVES = ("length", "corrections", "probability")

# flag -> Parameters field
PARAMETER_FLAGS = {
    "alpha1": "vertical limit on arrival at a V point (error units)",
    "alpha2": "horizontal limit on arrival at a V point",
    "beta1": "vertical limit on arrival at an H point",
    "beta2": "horizontal limit on arrival at an H point",
    "theta": "limit of both errors on arrival at B",
    "delta": "error growth per metre flown",
    "turn_radius": "minimum turning radius in metres (0: straight legs)",
    "p_success": "success probability of a correction at an unreliable point",
    "fail_residual": "residual error after a failed correction",
    "max_climb_angle": "largest climb (flight-path) angle in degrees (90: unlimited)",
    "max_descent_angle": "largest descent angle in degrees (90: unlimited)",
    "reserve": "flight reserve in metres: keep every error within its limit even when the "
    "aircraft flies this much more than planned between two resets",
    "approach": "straight run-in in metres: every leg with turns arrives on a tangent at least "
    "this long (default 0, or derived from the autopilot with --firmware/--vehicle-from)",
    "departure": "straight run-out in metres: every leg with turns leaves its point this far "
    "straight on before it turns (departure waypoint; default 0, or derived like --approach)",
}
# The aircraft beyond the planning parameters.
VEHICLE_FLAGS = {
    "cruise_airspeed": "cruise airspeed in m/s",
    "max_bank_angle": "bank limit in degrees: with --cruise-airspeed gives the turning radius "
    "R = V^2 / (g tan(bank)) instead of --turn-radius",
}


def add_scenario_arguments(parser: argparse.ArgumentParser, positional: bool = True) -> None:
    if positional:
        parser.add_argument(
            "scenario",
            help="scenario file: .toml, points .csv (x,y,z or lat,lon,alt), .geojson or "
            "contest .xlsx",
        )
    group = parser.add_argument_group("scenario parameters (override the scenario file)")
    for name, help_text in PARAMETER_FLAGS.items():
        group.add_argument(f"--{name.replace('_', '-')}", dest=name, type=float, help=help_text)
    for name, help_text in VEHICLE_FLAGS.items():
        group.add_argument(f"--{name.replace('_', '-')}", dest=name, type=float, help=help_text)
    group.add_argument(
        "--leg-model",
        choices=LEG_MODELS,
        help="how legs are flown with a turning radius > 0: airplane (horizontal turns, climb "
        "limits, helices; the default) or cs3d (tilted-plane Dubins, earlier releases' model)",
    )
    group.add_argument(
        "--heading-at-a", type=_vector, help="initial heading at A as X,Y,Z (default: free)"
    )
    group.add_argument("--origin", help="georeference LAT,LON[,ALT]")


def _vector(text: str) -> tuple[float, float, float]:
    try:
        parts = tuple(float(t) for t in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z numbers, got {text!r}") from None
    if len(parts) != 3 or not all(math.isfinite(p) for p in parts) or not any(parts):
        raise argparse.ArgumentTypeError(f"expected a non-zero X,Y,Z vector, got {text!r}")
    return parts  # type: ignore[return-value]


def load_scenario_from_args(args: argparse.Namespace, path: str | None = None) -> Scenario:
    from gcs_planner.scenario.georef import parse_origin
    from gcs_planner.scenario.readers import load_scenario

    overrides: dict = {
        name: getattr(args, name, None) for name in (*PARAMETER_FLAGS, *VEHICLE_FLAGS)
    }
    overrides["leg_model"] = getattr(args, "leg_model", None)
    overrides["heading_at_a"] = getattr(args, "heading_at_a", None)
    origin = getattr(args, "origin", None)
    overrides["origin"] = None if origin is None else parse_origin(origin)
    path = path if path is not None else args.scenario
    if path is None:
        raise InputError("no scenario given")
    return load_scenario(path, overrides)


def add_plan_arguments(parser: argparse.ArgumentParser) -> None:
    """The flags that say what to plan and which route to choose (plan, dry-run)."""
    parser.add_argument(
        "--objectives",
        help="comma-separated subset of length,corrections,probability, each at most once: the "
        "front is reported over these alone (one objective: its one optimal route; default: "
        "length,corrections, plus probability when the scenario has unreliable points)",
    )
    parser.add_argument(
        "--choose",
        default="compromise",
        choices=CHOICES,
        help="route choice among the routes that reach --min-probability (default compromise)",
    )
    parser.add_argument(
        "--weights", help="weights of the objectives for a weighted compromise, e.g. 1,0.5"
    )
    parser.add_argument(
        "--max-corrections", type=int, help="consider routes with at most K corrections"
    )
    parser.add_argument(
        "--min-probability",
        type=float,
        default=DEFAULT_MIN_PROBABILITY,
        metavar="P",
        help="choose only among front routes that arrive with probability >= P (default "
        f"{DEFAULT_MIN_PROBABILITY:g}; 0 for the plain compromise); when none does, the most "
        "reliable route is chosen, and it is exported only with --allow-risky",
    )
    budget = parser.add_argument_group(
        "search budget (turns and the probability objective: a branch and bound that proves "
        "its front by exhausting its queue; when the budget ends it first, each route's gap is "
        "reported)"
    )
    budget.add_argument(
        "--time-limit",
        type=_seconds,
        default=DEFAULT_TIME_LIMIT,
        metavar="SECONDS",
        help=f"stop the branch and bound after this many seconds of CPU in all, numba's "
        f"compiling not counted, so a busy machine proves what a quiet one does (default "
        f"{DEFAULT_TIME_LIMIT:g}; 'none' for no limit); past it the bounds built before the "
        "search are cut short or skipped, and the statement says what stopped it; reading the "
        "scenario and building its reach graph are not interrupted",
    )
    budget.add_argument(
        "--max-labels",
        type=_labels,
        metavar="N",
        help="partial routes each search may expand (default and 0: no limit, --time-limit "
        "bounds the search); with turns each expanded route may first be probed, up to 1,000 "
        "labels of the floor's relaxation, counted apart",
    )
    budget.add_argument(
        "--progress",
        action="store_true",
        help="show the search's progress on stderr even when it is not a terminal (plain "
        "lines, one every 10 s; default: only on a terminal)",
    )
    add_quiet_argument(budget)


class _DeprecatedAlias(argparse.Action):
    """A flag kept under its old name: it stores as the new one does and says it is deprecated."""

    def __init__(self, *args: object, new: str = "", **kwargs: object) -> None:
        self.new = new
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]

    def __call__(self, parser, namespace, values, option_string=None):  # type: ignore[no-untyped-def]
        print(
            f"gcs-planner: note: {option_string} is deprecated, use {self.new} (same values)",
            file=sys.stderr,
        )
        setattr(namespace, self.dest, values)


def add_autopilot_argument(
    parser: argparse.ArgumentParser | argparse._ArgumentGroup,
    *,
    help: str,
    default: str | None = None,
    old: Sequence[str] = ("--firmware",),
) -> None:
    """``--autopilot {ardupilot,px4}`` (stored as ``args.autopilot``), the one word for the
    autopilot on every command; ``old`` are the names it had before (``--firmware``,
    ``--flavour``), still taken, with a note that they are deprecated."""
    names = tuple(AUTOPILOTS)
    parser.add_argument("--autopilot", choices=names, default=default, help=help)
    for flag in old:
        parser.add_argument(
            flag,
            dest="autopilot",
            choices=names,
            action=_DeprecatedAlias,
            new="--autopilot",
            help=argparse.SUPPRESS,
        )


def add_quiet_argument(parser: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """``--quiet``, the same on every command that shows progress (plan, dry-run, upload,
    download, sweep)."""
    parser.add_argument(
        "--quiet", action="store_true", help="no progress display on stderr (even on a terminal)"
    )


def check_link_flags(args: argparse.Namespace) -> None:
    """The link's waits (upload, download, fly: ``add_link_arguments``): --timeout and --wait
    finite seconds > 0, --retries a whole number >= 0; InputError naming the flag otherwise.
    (A wait of -1 s or NaN would otherwise fail as a link error, after the link is opened.)"""
    for flag, value in (("--timeout", args.timeout), ("--wait", args.wait)):
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"must be a finite number of seconds > 0, got {value:g}", field=flag)
    if args.retries < 0:
        raise InputError(f"must be a whole number >= 0, got {args.retries}", field="--retries")


def _seconds(text: str) -> float | None:
    if text.strip().lower() in ("none", "inf"):
        return None  # no time limit
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected seconds >= 0, got {text!r}")
    return value


def _labels(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected labels >= 0, got {text!r}")
    return value


def _suggest_compiling(quiet: bool) -> None:
    """After a plan, when a kernel the commands use is not in numba's cache (a first plan
    after installing runs in Python: core/bnb/context.first_run): compile them in a background
    process once this command has ended (gcs_planner/runtime/background_compile.py), and say so
    on a terminal."""
    from gcs_planner.runtime import background_compile

    if not background_compile.after_this_command():
        return
    if not quiet and on_terminal(sys.stderr):
        print(
            "gcs-planner: compiling its kernels once in the background (low priority) for "
            f"faster later plans; {background_compile.VARIABLE}=0 turns this off",
            file=sys.stderr,
        )


def parse_objectives(text: str, known: Sequence[str]) -> tuple[str, ...]:
    """``--objectives`` as names: each of ``known``, at most once, at least one."""
    names = [o.strip() for o in text.split(",") if o.strip()]
    choose = f"give a comma-separated subset of {','.join(known)}"
    if not names:
        raise InputError(f"no objective given ({text!r}); {choose}", field="--objectives")
    unknown = [o for o in names if o not in known]
    if unknown:
        raise InputError(
            f"unknown objective(s) {', '.join(map(repr, unknown))}; {choose}", field="--objectives"
        )
    twice = sorted({o for o in names if names.count(o) > 1})
    if twice:
        raise InputError(
            f"{', '.join(twice)} given more than once in {text!r}; {choose}", field="--objectives"
        )
    return tuple(names)


def check_plan_flags(
    args: argparse.Namespace,
) -> tuple[tuple[str, ...] | None, list[float] | None]:
    """(objectives, weights) of the flags of :func:`add_plan_arguments`, checked: InputError
    naming the flag otherwise. Cheap, so a command calls it before it reads the scenario."""
    objectives = None
    if args.objectives is not None:  # '' is a mistake, not the default
        objectives = parse_objectives(args.objectives, OBJECTIVES)
    if args.max_corrections is not None and args.max_corrections < 0:
        raise InputError(
            f"must be a whole number >= 0, got {args.max_corrections}", field="--max-corrections"
        )
    weights = None
    if args.weights:
        try:
            weights = [float(w) for w in args.weights.split(",")]
        except ValueError:
            raise InputError(f"not numbers: {args.weights!r}", field="--weights") from None
    if not 0.0 <= args.min_probability <= 1.0:
        raise InputError(
            f"{args.min_probability:g} is not a probability (0 to 1)", field="--min-probability"
        )
    return objectives, weights


def plan_from_args(args: argparse.Namespace, scenario: Scenario) -> Plan:
    """Plan ``scenario`` with the flags of :func:`add_plan_arguments`; bad flags are InputError."""
    from gcs_planner.core.planner import plan

    objectives, weights = check_plan_flags(args)
    from gcs_planner.runtime.progress import SearchProgress

    # The CLI's 0 is "no limit", as unset is (the library's max_labels=0 allows no label).
    max_labels = getattr(args, "max_labels", None)
    progress = SearchProgress(
        sys.stderr,
        quiet=getattr(args, "quiet", False),
        force=getattr(args, "progress", False),
    )
    from gcs_planner.runtime import compile_notice, interrupt

    # Before the progress display starts (one display on the terminal at a time): a fresh
    # install's first plan compiles for tens of seconds before it can show any progress.
    compile_notice.maybe_notify(sys.stderr, quiet=getattr(args, "quiet", False))

    # Ctrl-C inside a compiled kernel must not raise where numba's C code would turn it into
    # a SystemError: taken as a flag during the plan, raised from Python (issue 28).
    try:
        with interrupt.deferred():
            result = plan(
                scenario,
                objectives=objectives,
                choice=args.choose,
                weights=weights,
                max_corrections=args.max_corrections,
                min_probability=args.min_probability,
                max_labels=max_labels or None,
                time_limit=getattr(args, "time_limit", DEFAULT_TIME_LIMIT),
                progress=progress if progress.enabled else None,
            )
    except ValueError as exc:
        raise InputError(str(exc)) from None
    finally:
        progress.finish()
    _suggest_compiling(getattr(args, "quiet", False))
    return result
