"""The capture check (docs/model.md, "Flight in the real world"): at each correction point of a
route, the position error on arrival in metres plus the autopilot's tracking allowance must fit
the landmark's capture radius, or the true track may pass it outside and the correction is not
made. The errors are the worst over the correction outcomes the plan allows: a failed fix at an
unreliable point leaves min(error, r), so the errors after it exceed the all-success figures of
the route table. The states and their outcomes are the probability model's own
(:func:`gcs_planner.core.probability.propagate`).

In a design turbulence each capture also carries the altitude loop's height error, up to the
vertical allowance z of its altitude (:mod:`gcs_planner.aircraft.altitude_hold`). It lies along
the INS's vertical error, orthogonal to the horizontal one, and either sign may meet either
sign: the 3D error is at most sqrt((v + z)^2 + h^2), and the tracking allowance (a distance in
any direction) adds to it by the triangle inequality. B, which the dry run also demands within
the capture radius, is checked then too."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace

from gcs_planner.aircraft.altitude_hold import AltitudeHold
from gcs_planner.core.probability import propagate
from gcs_planner.core.route import Stop
from gcs_planner.scenario.model import Kind, Parameters, Scenario, altitude_of


def capture_check(
    stops: Sequence[Stop],
    error_unit: float,
    capture_radius: float,
    allowance: float,
    params: Parameters,
    vertical: Callable[[str], float] | None = None,
) -> dict[str, object]:
    """Point by point along a route's ``stops``: the worst error on arrival over the outcomes,
    sqrt(v^2 + h^2) * ``error_unit`` (the two errors are orthogonal), plus ``allowance``, against
    ``capture_radius``. Outcomes that arrive beyond a point's limits are lost there (counted in
    the probability) and not carried on. ``vertical`` gives a point's vertical allowance (m, by
    its id: the design turbulence's), added to the vertical error, B then checked too. Returns
    the worst point, its need, and the first point that does not fit (None when all do)."""
    first, worst, worst_need = None, None, -math.inf
    states: dict[tuple[float, float], float] = {(0.0, 0.0): 1.0}  # metres since each reset
    for stop in stops[1:]:
        leg = 0.0 if stop.leg is None else stop.leg.length
        v_lim, h_lim = params.limits_m(stop.kind)
        reached = [(v + leg, h + leg) for v, h in states]
        # A point no outcome reaches within its limits is judged on all of them.
        arrivals = [(v, h) for v, h in reached if v <= v_lim and h <= h_lim] or reached
        states, _ = propagate(states, leg, stop.kind, stop.unreliable, params)
        captured = ("V", "H") if vertical is None else ("V", "H", "B")
        if stop.kind.name in captured and arrivals:
            d = params.delta  # metres flown -> error units, as the route table gives them
            z = 0.0 if vertical is None else vertical(stop.id) / error_unit
            metres = max(math.hypot(v * d + z, h * d) for v, h in arrivals) * error_unit
            need = metres + allowance
            if need > worst_need:
                worst, worst_need = stop.id, need
            if first is None and need > capture_radius:
                first = {"point": stop.id, "need_m": need}
                if vertical is not None:
                    first["vertical_allowance_m"] = z * error_unit
        if not states:
            break  # nothing arrives further
    return {
        "error_unit_m": error_unit,
        "capture_radius_m": capture_radius,
        "tracking_allowance_m": allowance,
        "over_outcomes": True,
        "worst_point": worst,
        "worst_need_m": None if worst is None else worst_need,
        "first_not_captured": first,
    }


def capture_warning(check: dict) -> str | None:
    """The plan's warning when a correction point's need exceeds its capture radius."""
    first = check["first_not_captured"]
    if first is None:
        return None
    return (
        f"point {first['point']} is likely missed: its error on arrival plus the tracking "
        f"allowance is {first['need_m']:.2f} m, beyond the capture radius "
        f"{check['capture_radius_m']:g} m ({check['error_unit_m']:g} m per error unit, "
        f"allowance {check['tracking_allowance_m']:g} m"
        + (", worst over the correction outcomes" if check.get("over_outcomes") else "")
        + (
            f", vertical allowance {first['vertical_allowance_m']:.2f} m for the design turbulence"
            if first.get("vertical_allowance_m")
            else ""
        )
        + "); the correction there, and those after it, may not be made"
    )


def turbulence_capture(
    stops: Sequence[Stop], scenario: Scenario, allowance: float, hold: AltitudeHold
) -> dict[str, object]:
    """The capture check of a route in ``hold``'s design turbulence, each capture (B too) with
    its vertical allowance k sigma_h at its altitude, and its warning; the record names the
    turbulence, the loop, k and each point's sigma_h and allowance (the plan JSON's
    ``capture``)."""
    alt = altitude_of(scenario)
    check = capture_check(
        stops,
        scenario.error_unit,
        scenario.capture_radius,
        allowance,
        scenario.params,
        vertical=lambda pid: hold.allowance(alt(pid)),
    )
    points = {
        s.id: {
            "sigma_h_m": hold.sigma_h(alt(s.id)),
            "vertical_allowance_m": hold.allowance(alt(s.id)),
        }
        for s in stops[1:]
        if s.kind.name in ("V", "H", "B")
    }
    return {
        **check,
        "warning": capture_warning(check),
        "turbulence": {**hold.to_dict(), "describe": hold.describe(), "points": points},
    }


def with_design_turbulence(scenario: Scenario, hold: AltitudeHold) -> Scenario:
    """``scenario`` with each V, H and B point's vertical allowance k sigma_h at its altitude
    (``Scenario.capture_vertical``): the search then keeps only routes whose captures fit
    (core/capture_front.py)."""
    alt = altitude_of(scenario)
    captures = (Kind.V, Kind.H, Kind.B)
    vertical = tuple(
        hold.allowance(alt(pid)) if Kind(int(kind)) in captures else 0.0
        for pid, kind in zip(scenario.ids, scenario.kind, strict=True)
    )
    return replace(scenario, capture_vertical=vertical)
