"""The library's verbs beyond the planner itself: read a scenario with keyword overrides, choose
another route from a plan's front, write a route as a mission file.

They are what ``from gcs_planner import ...`` offers (see the package docstring); the command
line does the same through the same functions and policy.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gcs_planner.core.choose import (
    DEFAULT_MIN_PROBABILITY,
    RiskyRouteWarning,
    check_exportable,
    choose_index,
)
from gcs_planner.errors import InputError
from gcs_planner.scenario.model import Origin

if TYPE_CHECKING:
    from gcs_planner.core.planner import Plan
    from gcs_planner.scenario.model import Scenario

# File suffix -> export format (gcs_planner.mission.export.FORMATS).
SUFFIX_FORMATS = {
    ".plan": "plan",
    ".waypoints": "waypoints",
    ".geojson": "geojson",
    ".kml": "kml",
    ".csv": "csv",
}


def load_scenario(
    path: str | os.PathLike[str], *, autopilot: str | None = None, **overrides: Any
) -> Scenario:
    """Read a scenario: a scenario TOML, a points CSV (local metres), a geographic CSV
    (``id,lat,lon,alt,kind,unreliable``), GeoJSON points, or a contest workbook (.xlsx), as the
    planning problem ``gcs-planner plan`` builds from it: a TOML's ``[vehicle]`` autopilot
    terms and ``[environment]`` derive the envelope and the reserve, and an aircraft with climb
    limits and turns keeps straight at every landmark for as long as ``autopilot``'s path
    follower needs (``--autopilot``; ArduPilot when None). ``autopilot`` given also fills what
    the scenario leaves unstated with that autopilot's shipped defaults, as ``--autopilot``.

    Keyword overrides win over the file, as flags do on the command line: the model's parameters
    (``alpha1`` ... ``delta``, ``turn_radius``, ``p_success``, ``fail_residual``), the aircraft
    (``max_climb_angle``, ``max_descent_angle``, ``cruise_airspeed``, ``max_bank_angle``,
    ``leg_model``), ``heading_at_a`` as (x, y, z) and ``origin`` as an :class:`Origin` or
    (lat, lon[, alt]). Bad input raises :class:`~gcs_planner.errors.InputError` naming the file,
    row and field.
    """
    from gcs_planner.scenario.readers import OVERRIDE_KEYS
    from gcs_planner.scenario.readers import load_scenario as read

    unknown = sorted(set(overrides) - set(OVERRIDE_KEYS))
    if unknown:
        raise TypeError(
            f"load_scenario() got unknown override(s) {', '.join(unknown)}; "
            f"known: {', '.join(OVERRIDE_KEYS)}"
        )
    origin = overrides.get("origin")
    if origin is not None and not isinstance(origin, Origin):
        try:
            overrides["origin"] = Origin(*(float(v) for v in origin))
        except (TypeError, ValueError):
            raise InputError(
                f"must be an Origin or (lat, lon[, alt]), got {origin!r}", field="origin"
            ) from None
    scenario = read(path, overrides)
    from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT
    from gcs_planner.aircraft.derive import AircraftTerms, derive_envelope

    stated = {k: overrides[k] for k in _AIRCRAFT_OVERRIDES if overrides.get(k) is not None}
    terms = AircraftTerms(autopilot=autopilot, **stated)
    return derive_envelope(terms, scenario, flown_by=autopilot or DEFAULT_AUTOPILOT)


# The overrides that state the aircraft (the flags of the same names on the command line).
_AIRCRAFT_OVERRIDES = (
    "cruise_airspeed", "max_bank_angle", "turn_radius", "max_climb_angle", "max_descent_angle",
    "approach", "departure",
)  # fmt: skip


def choose(
    plan: Plan,
    how: str = "compromise",
    *,
    weights: Sequence[float] | None = None,
    min_probability: float = DEFAULT_MIN_PROBABILITY,
) -> Plan:
    """The same plan with another route chosen from its front: ``how`` is "compromise",
    "shortest", "fewest" or "most-reliable", among the routes at least ``min_probability``
    likely to arrive (the most reliable one when none is; ``threshold_met`` then says so)."""
    chosen, met = choose_index(
        plan.routes,
        choice=how,
        weights=weights,
        min_probability=min_probability,
        use_probability="probability" in plan.objectives,
    )
    return replace(
        plan, chosen=chosen, choice=how, min_probability=min_probability, threshold_met=met
    )


def write_mission(
    plan: Plan,
    path: str | os.PathLike[str],
    *,
    route_index: int | None = None,
    allow_risky: bool = False,
    **mission_options: Any,
) -> Path:
    """Write a route of ``plan`` (the chosen one by default) as the file ``path`` names by its
    suffix: ``.plan`` (QGroundControl), ``.waypoints`` (Mission Planner), ``.geojson``, ``.kml``
    or ``.csv``. ``mission_options`` are the exporter's (``firmware``, ``altitude_frame``,
    ``acceptance_radius``, ``cruise_speed``, ``at_end``, ``origin``).

    A route less likely to arrive than the plan's ``min_probability`` raises
    :class:`~gcs_planner.core.choose.RiskyRouteError` unless ``allow_risky``; any route below the
    safe default is written with a :class:`~gcs_planner.core.choose.RiskyRouteWarning`.
    """
    from gcs_planner.mission.export import export
    from gcs_planner.mission.plan_json import plan_to_dict

    out = Path(path)
    fmt = SUFFIX_FORMATS.get(out.suffix.lower())
    if fmt is None:
        raise InputError(
            f"unknown mission file type {out.suffix!r}: one of {', '.join(SUFFIX_FORMATS)}",
            file=str(out),
        )
    k = plan.chosen if route_index is None else route_index
    if not 0 <= k < len(plan.routes):
        raise InputError(f"route index {k} is not in the front (0..{len(plan.routes) - 1})")
    warning = check_exportable(plan.routes[k].probability, k, plan.min_probability, allow_risky)
    if warning:
        warnings.warn(warning, RiskyRouteWarning, stacklevel=2)
    written, _ = export(plan_to_dict(plan), fmt, out, route_index=k, **mission_options)
    return written
