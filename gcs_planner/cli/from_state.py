"""``plan --from-state POINT:V,H[:HEADING] [--flown IDS]``: plan the continuation from a state
mid-flight (core/from_state.py), e.g. after a failed fix at POINT."""

from __future__ import annotations

import argparse
import math

from gcs_planner.core.from_state import FlightState, compass_heading, state_scenario
from gcs_planner.errors import GcsPlannerError, InputError
from gcs_planner.scenario.model import Scenario


def add_from_state_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--from-state",
        metavar="POINT:V,H[:HEADING]",
        help="plan from a state mid-flight instead of from A: at point POINT (its fix made or "
        "failed), with vertical and horizontal errors V and H in the scenario's error units "
        "(as alpha1 ...), flying compass HEADING degrees (0 north, 90 east; default: any)",
    )
    parser.add_argument(
        "--flown",
        metavar="IDS",
        help="with --from-state, comma-separated ids of the points already flown (A and POINT "
        "are counted anyway): the continuation passes none of them again",
    )


def apply_from_state(args: argparse.Namespace, scenario: Scenario) -> Scenario:
    """The scenario of the continuations from ``--from-state`` (``scenario`` without it)."""
    text = getattr(args, "from_state", None)
    if text is None:
        if getattr(args, "flown", None):
            raise InputError("--flown needs --from-state", field="--flown")
        return scenario
    parts = text.split(":")
    if len(parts) not in (2, 3) or not parts[0]:
        raise InputError(f"expected POINT:V,H[:HEADING], got {text!r}", field="--from-state")
    try:
        at = scenario.index_of(parts[0].strip())
    except KeyError:
        raise InputError(
            f"no point {parts[0]!r} in {scenario.name}", field="--from-state"
        ) from None
    try:
        v_units, h_units = (float(x) for x in parts[1].split(","))
    except ValueError:
        raise InputError(
            f"errors must be two numbers V,H, got {parts[1]!r}", field="--from-state"
        ) from None
    heading = None
    if len(parts) == 3:
        try:
            degrees = float(parts[2])
        except ValueError:
            raise InputError(
                f"heading must be degrees, got {parts[2]!r}", field="--from-state"
            ) from None
        if not math.isfinite(degrees):
            raise InputError(f"heading must be finite, got {parts[2]!r}", field="--from-state")
        heading = compass_heading(degrees)
    for name, value in (("V", v_units), ("H", h_units)):
        if not (math.isfinite(value) and value >= 0.0):
            raise InputError(f"error {name} must be >= 0, got {value:g}", field="--from-state")
    flown = {scenario.start, at}
    for pid in (args.flown or "").split(","):
        if pid.strip():
            try:
                flown.add(scenario.index_of(pid.strip()))
            except KeyError:
                raise InputError(
                    f"no point {pid.strip()!r} in {scenario.name}", field="--flown"
                ) from None
    delta = scenario.params.delta
    state = FlightState(at, heading, v_units / delta, h_units / delta, frozenset(flown))
    try:
        return state_scenario(scenario, state)[0]
    except GcsPlannerError as exc:
        raise InputError(str(exc), field="--from-state") from None
