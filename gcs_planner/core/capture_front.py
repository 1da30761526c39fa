"""The exact front whose every capture fits in the design turbulence (docs/model.md, "Turbulence
in the plan"): only routes at each of whose V, H and B points the worst error on arrival over
the correction outcomes, with the point's vertical allowance on the vertical error, plus the
tracking allowance, fits the capture radius (the condition of
:func:`gcs_planner.core.capture.capture_check`; a point no outcome that can happen reaches
within its limits does not fit).

Whether a capture fits depends only on the route up to that point, and a prefix whose capture
does not fit has no extension that fits, so ``within_captures`` proves the constrained front in
three steps, each exact:

1. A point whose allowance alone (no error at all) exceeds the capture radius is never a
   capture that fits; when that holds of B, no route fits.
2. The front of every route (the engines') is the front of the fitting routes when each of its
   routes fits: every fitting route is matched or beaten by a front route, which fits too.
3. Otherwise ``captured_front`` searches the fitting routes: depth first over simple routes
   (no dominance among partial routes: a dominating one may carry an outcome that does not
   fit), a partial route dropped when a capture along it does not fit, when no error state
   survives, or when a route found matches or beats every completion of it (its length plus
   the chord to B, its corrections, its probability). With an endurance the flight time
   prunes as in core/endurance_front.py.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from gcs_planner.aircraft.profile import TRACKING_ALLOWANCE_M
from gcs_planner.core.bnb import flown_route
from gcs_planner.core.engines import EngineResult
from gcs_planner.core.probability import PROB_EPS, State, propagate, success_probability
from gcs_planner.core.reach import arrival_limits_m
from gcs_planner.core.route import Route
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

_LENGTH_TIE_M = 1e-6  # lengths within this are the same length (as the planner's front)
# The partial routes the depth-first search extends when the planner sets no label budget:
# without dominance the search is exponential, and a front it has not finished says so.
DEFAULT_CAPTURE_LABELS = 5_000
CAPTURED = (Kind.V, Kind.H, Kind.B)


def arrival_fits(scenario: Scenario, point: int, arrived: Mapping[State, float]) -> bool:
    """Whether every error state ``arrived`` at ``point`` (metres flown since each reset, the
    states within its limits) passes within its capture radius with the point's vertical
    allowance and the tracking allowance (true at points that capture nothing)."""
    vertical = scenario.capture_vertical
    if vertical is None or Kind(int(scenario.kind[point])) not in CAPTURED:
        return True
    d, unit = scenario.params.delta, scenario.error_unit
    z = vertical[point] / unit
    # The arithmetic of capture_check, so that a boundary case is decided identically.
    worst = max(math.hypot(v * d + z, h * d) for v, h in arrived) * unit
    return not worst + TRACKING_ALLOWANCE_M > scenario.capture_radius


def route_fits(scenario: Scenario, route: Route) -> bool:
    """Whether every capture of ``route`` fits: at each point, over the correction outcomes
    that can happen and arrive within its limits (none arriving: it does not fit), the
    condition of :func:`arrival_fits`, the outcomes those of the probability model."""
    params = scenario.params
    states: dict[State, float] = {scenario.initial_errors: 1.0}
    for stop in route.stops[1:]:
        leg = 0.0 if stop.leg is None else stop.leg.length
        top_v, top_h = params.limits_m(stop.kind)
        arrived = [(v + leg, h + leg) for v, h in states]
        arrived = [(v, h) for v, h in arrived if v <= top_v and h <= top_h]
        point = scenario.index_of(stop.id)
        if not arrived or not arrival_fits(scenario, point, dict.fromkeys(arrived, 0.0)):
            return False
        states, _ = propagate(states, leg, stop.kind, stop.unreliable, params)
    return True


@dataclass
class CapturedFront:
    """What ``captured_front`` found: (length, corrections, probability, points) per front
    route, whether the search ran to the end (False: the label budget ended it), and how many
    partial routes it extended."""

    routes: list[tuple[float, int, float, tuple[int, ...]]]
    exhausted: bool
    labels: int


def captured_front(
    scenario: Scenario,
    probability: bool,
    max_corrections: int | None = None,
    max_labels: int | None = None,
) -> CapturedFront:
    """The exact Pareto front of (length, corrections[, probability]) over the simple routes
    whose every capture fits (step 3 of the module's proof)."""
    model = scenario_leg_model(scenario)
    xyz, params, n, end = scenario.xyz, scenario.params, scenario.n, scenario.end
    kind = [Kind(int(c)) for c in scenario.kind]
    kmax = n if max_corrections is None else max_corrections
    chord = np.linalg.norm(xyz[None, :, :] - xyz[:, None, :], axis=2)
    chord_to_b = chord[:, end]
    lim_v, lim_h = arrival_limits_m(scenario)
    timed = _time_bound(scenario)
    usable = np.array([t == end or _may_fit(scenario, t) for t in range(n)])
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a)
    found: list[tuple[float, int, float, tuple[int, ...]]] = []
    labels, stopped = 0, False

    def covered(length: float, k: int, mass: float) -> bool:
        return any(_covers(f, (length, k, mass), probability) for f in found)

    def extend(path: tuple[int, ...], heading, length: float, seconds: float, states, sure) -> None:  # noqa: ANN001, E501
        nonlocal labels, stopped
        if max_labels is not None and labels >= max_labels:
            stopped = True
            return
        labels += 1
        i, k = path[-1], len(path) - 1
        # A leg is at least its chord: the points no error state can reach within the limits.
        v_min, h_min = min(v for v, _ in states), min(h for _, h in states)
        near = usable & (v_min + chord[i] <= lim_v) & (h_min + chord[i] <= lim_h)
        options = []
        for t in np.flatnonzero(near).tolist():
            if t in path or (t != end and k + 1 > kmax):
                continue
            leg = model.leg(xyz[i], heading, xyz[t])
            if not np.isfinite(leg.length):
                continue
            nt = 0.0 if timed is None else timed(i, t, seconds, leg.length)
            if not math.isfinite(nt):
                continue
            options.append((length + leg.length + chord_to_b[t], t, leg, nt))
        for _, t, leg, nt in sorted(options, key=lambda o: o[0]):
            top_v, top_h = params.limits_m(kind[t])
            arrived = [(v + leg.length, h + leg.length) for v, h in states]
            arrived = [(v, h) for v, h in arrived if v <= top_v and h <= top_h]
            if not arrived or not arrival_fits(scenario, t, dict.fromkeys(arrived, 0.0)):
                continue
            # The captures are judged over every correction outcome (as capture_check);
            # without the probability objective a route is feasible on its all-success path.
            after, _ = propagate(states, leg.length, kind[t], bool(scenario.unreliable[t]), params)
            now, _ = propagate(sure, leg.length, kind[t], False, params)
            if not after or not (probability or now):
                continue
            mass = min(1.0, sum(after.values())) if probability else 1.0
            nl = length + leg.length
            if t == end:
                if not covered(nl, k, mass):
                    found[:] = [f for f in found if not _covers((nl, k, mass), f, probability)]
                    found.append((nl, k, mass, (*path, t)))
                continue
            if covered(nl + chord_to_b[t], k + 1, mass):
                continue
            extend((*path, t), leg.heading_out, nl, nt, after, now)
            if stopped:
                return

    first = {scenario.initial_errors: 1.0}
    extend((scenario.start,), heading_a, 0.0, 0.0, first, dict(first))
    found.sort(key=lambda f: (f[1], f[0]))
    return CapturedFront(found, not stopped, labels)


def _may_fit(scenario: Scenario, point: int) -> bool:
    """Step 1: whether a capture at ``point`` fits with no error at all."""
    return arrival_fits(scenario, point, {(0.0, 0.0): 1.0})


def _time_bound(scenario: Scenario) -> Callable[[int, int, float, float], float] | None:
    """With an endurance: the seconds after a leg, inf when even the least time from there to
    B exceeds it (core/flight_time.py, as core/endurance_front.py prunes); None without."""
    if getattr(scenario, "endurance", None) is None:
        return None
    from gcs_planner.core.flight_time import ground_speeds, seconds_to_b

    limit_s = float(scenario.endurance) * 60.0  # type: ignore[arg-type]
    to_b = seconds_to_b(scenario)
    xyz = scenario.xyz

    def after(i: int, t: int, seconds: float, length: float) -> float:
        vg = float(ground_speeds(scenario, xyz[i], xyz[t])[0])
        nt = seconds + length / vg if vg > 0.0 else math.inf
        return nt if nt + to_b[t] <= limit_s else math.inf

    return after


def _covers(a: tuple, b: tuple, probability: bool) -> bool:
    """Route values ``a`` (length, k, mass) match or beat ``b``'s in every objective."""
    return (
        a[0] <= b[0] + _LENGTH_TIE_M
        and a[1] <= b[1]
        and (not probability or a[2] >= b[2] - PROB_EPS)
    )


def within_captures(
    scenario: Scenario,
    run_engine: Callable[[], EngineResult],
    use_probability: bool,
    max_corrections: int | None,
    max_labels: int | None,
) -> EngineResult:
    """The engine's result restricted to the routes whose every capture fits (the module's
    three steps); with no route, its statement says the captures are why."""
    why_room = (
        f"the capture radius {scenario.capture_radius:g} m less the tracking allowance "
        f"{TRACKING_ALLOWANCE_M:g} m"
    )
    vertical = scenario.capture_vertical or ()
    if not _may_fit(scenario, scenario.end):
        why = (
            f"no route fits its captures in the design turbulence: B's vertical allowance "
            f"{vertical[scenario.end]:.2f} m alone exceeds {why_room} "
            '(docs/model.md, "Turbulence in the plan")'
        )
        return EngineResult([], [], True, why, {"captures_fit": 0})
    result = run_engine()
    if not result.routes:
        return result
    fits = [route_fits(scenario, r) for r in result.routes]
    if all(fits):
        result.statement += (
            "; every capture of every front route fits in the design turbulence, so this is "
            "the front of the routes whose captures fit"
        )
        return result
    max_labels = max_labels or DEFAULT_CAPTURE_LABELS
    found = captured_front(scenario, use_probability, max_corrections, max_labels)
    result.stats["capture_labels"] = found.labels
    worst = max((v for v in vertical), default=0.0)
    if not found.routes:
        if not found.exhausted:
            why = (
                "no route whose captures fit in the design turbulence found within the budget "
                f"of {max_labels} labels, so infeasibility is not proven"
            )
            return EngineResult([], [], False, why, result.stats)
        why = (
            "no route fits its captures in the design turbulence (exhaustive search of the "
            f"routes whose captures fit): the vertical allowances, up to {worst:.2f} m, leave "
            f"too little of {why_room} for the INS error on arrival "
            '(docs/model.md, "Turbulence in the plan")'
        )
        return EngineResult([], [], True, why, result.stats)
    routes = [_flown(scenario, points) for *_, points in found.routes]
    dropped = fits.count(False)
    if found.exhausted:
        statement = (
            "exact: the Pareto front of the routes whose every capture fits in the design "
            f"turbulence, proven by a search of them ({found.labels} labels; {dropped} route(s) "
            "of the front of all routes miss a capture)"
        )
        return EngineResult(routes, [r.length for r in routes], True, statement, result.stats)
    statement = (
        "not proven: the routes whose captures fit found before the budget of "
        f"{max_labels} labels ended the search (lower bounds 0)"
    )
    return EngineResult(routes, [0.0] * len(routes), False, statement, result.stats)


def _flown(scenario: Scenario, points: tuple[int, ...]) -> Route:
    """The route through ``points`` flown again, with its exact success probability."""
    route = flown_route(scenario, points)
    legs = [s.leg for s in route.stops[1:]]
    sp = success_probability(scenario, route.points, legs)
    return route.with_probabilities(sp.probability, sp.per_stop)
