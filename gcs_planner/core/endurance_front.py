"""The exact front within the aircraft's endurance (docs/model.md, "Endurance in the plan"):
only routes whose flight time in the design wind (``flight_time``) is within it.

Flight time is a resource along a route. ``within_endurance`` proves the constrained front in
three steps, each exact:

1. Every route needs at least the least chord time from A to B (``flight_time.seconds_to_b``):
   when that exceeds the endurance, no route is within it.
2. The front of every route (the engines') is the front within the endurance when each of its
   routes is within it: every route within the endurance is matched or beaten by a front route,
   which is within it too.
3. Otherwise ``timed_front`` searches the routes within it: depth first over simple routes (as
   the branch and bound with turns, no dominance among partial routes, so none where the
   dominating one could have taken longer), a partial route dropped when its time so far plus
   the least time to B exceeds the endurance, when no error state survives it, or when a route
   found within the endurance matches or beats every completion of it (its length plus the
   chord to B, its corrections, its probability).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from gcs_planner.core.bnb import flown_route
from gcs_planner.core.engines import EngineResult
from gcs_planner.core.flight_time import ground_speeds, route_minutes, seconds_to_b
from gcs_planner.core.probability import PROB_EPS, propagate, success_probability
from gcs_planner.core.route import Route
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

# Lengths within this many metres are the same length (as the planner's front).
_LENGTH_TIE_M = 1e-6


@dataclass
class TimedFront:
    """What ``timed_front`` found: (length, corrections, probability, seconds, points) per front
    route, and whether the search ran to the end (False: the label budget ended it)."""

    routes: list[tuple[float, int, float, float, tuple[int, ...]]]
    exhausted: bool
    labels: int


def timed_front(
    scenario: Scenario,
    limit_s: float,
    probability: bool,
    max_corrections: int | None = None,
    max_labels: int | None = None,
    to_b: np.ndarray | None = None,
    time_limit: float | None = None,
    seeds: Sequence[Route] = (),
) -> TimedFront:
    """The exact Pareto front of (length, corrections[, probability]) over the simple routes
    whose flight time is at most ``limit_s`` seconds (step 3 of the module's proof); within
    ``max_labels`` partial routes and ``time_limit`` seconds (None: unlimited), else not
    exhausted. ``seeds``: routes known within the endurance (the engine's), found from the
    start so that they prune at once."""
    deadline = None if time_limit is None else time.perf_counter() + time_limit
    model = scenario_leg_model(scenario)
    xyz, params, n, end = scenario.xyz, scenario.params, scenario.n, scenario.end
    kind = [Kind(int(c)) for c in scenario.kind]
    unreliable = scenario.unreliable if probability else np.zeros(n, dtype=bool)
    kmax = n if max_corrections is None else max_corrections
    to_b = seconds_to_b(scenario) if to_b is None else to_b
    chord_to_b = np.linalg.norm(xyz - xyz[end], axis=1)
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a)
    found: list[tuple[float, int, float, float, tuple[int, ...]]] = []
    labels = 0
    stopped = False

    def covered(length: float, k: int, mass: float) -> bool:
        """A route found matches or beats every route of at least ``length``, ``k``
        corrections and at most ``mass`` probability."""
        return any(_covers(f, (length, k, mass), probability) for f in found)

    def offer(values: tuple[float, int, float, float, tuple[int, ...]]) -> None:
        if not covered(values[0], values[1], values[2]):
            found[:] = [f for f in found if not _covers(values, f, probability)]
            found.append(values)

    def extend(path: tuple[int, ...], heading, length: float, seconds: float, states) -> None:  # noqa: ANN001
        nonlocal labels, stopped
        if (max_labels is not None and labels >= max_labels) or (
            deadline is not None and time.perf_counter() > deadline
        ):
            stopped = True
            return
        labels += 1
        i, k = path[-1], len(path) - 1
        # Every point not yet flown to (B alone once the corrections are spent).
        targets = np.array(
            [t for t in range(n) if t not in path and (t == end or k + 1 <= kmax)], np.int64
        )
        if len(targets) == 0:
            return
        flown, headings = model.lengths(xyz[i], heading, xyz[targets])
        vg = ground_speeds(scenario, xyz[i], xyz[targets])
        ok = np.isfinite(flown) & (vg > 0.0)
        after_s = seconds + np.where(ok, flown, 0.0) / np.where(ok, vg, 1.0)
        ok &= after_s + to_b[targets] <= limit_s
        order = np.flatnonzero(ok)
        order = order[np.argsort(length + flown[order] + chord_to_b[targets[order]], kind="stable")]
        for idx in order:
            t, d, nt = int(targets[idx]), float(flown[idx]), float(after_s[idx])
            after, _ = propagate(states, d, kind[t], bool(unreliable[t]), params)
            if not after:
                continue
            mass = min(1.0, sum(after.values())) if probability else 1.0
            nl = length + d
            if t == end:
                offer((nl, k, mass, nt, (*path, t)))
                continue
            if covered(nl + chord_to_b[t], k + 1, mass):
                continue
            extend((*path, t), None if headings is None else headings[idx], nl, nt, after)
            if stopped:
                return

    for route in seeds:
        mass = route.probability if probability else 1.0
        offer((route.length, route.corrections, mass, route_minutes(scenario, route) * 60.0,
               tuple(route.points)))  # fmt: skip
    if math.isfinite(to_b[scenario.start]) and to_b[scenario.start] <= limit_s:
        extend((scenario.start,), heading_a, 0.0, 0.0, {scenario.initial_errors: 1.0})
    found.sort(key=lambda f: (f[1], f[0]))
    return TimedFront(found, not stopped, labels)


def _covers(a: tuple, b: tuple, probability: bool) -> bool:
    """Route values ``a`` (length, k, mass) match or beat ``b``'s in every objective."""
    return (
        a[0] <= b[0] + _LENGTH_TIE_M
        and a[1] <= b[1]
        and (not probability or a[2] >= b[2] - PROB_EPS)
    )


def within_endurance(
    scenario: Scenario,
    run_engine: Callable[[], EngineResult],
    use_probability: bool,
    max_corrections: int | None,
    max_labels: int | None,
    time_limit: float | None = None,
) -> EngineResult:
    """The engine's result within ``scenario.endurance`` minutes (the module's three steps);
    with no route, its statement names the endurance and the least flight time a route
    needs."""
    limit_min = float(scenario.endurance)  # type: ignore[arg-type]
    limit_s = limit_min * 60.0
    to_b = seconds_to_b(scenario)
    least_min = float(to_b[scenario.start]) / 60.0
    if least_min > limit_min:
        why = (
            f"no route within the endurance of {limit_min:g} min: every route needs at least "
            f"{_minutes_text(least_min)} of flight in the design wind (the chords to B at the "
            'ground speed along each; docs/model.md, "Endurance in the plan")'
        )
        stats = {"endurance_min": limit_min, "least_flight_min": least_min}
        return EngineResult([], [], True, why, stats)
    result = run_engine()
    result.stats.update(endurance_min=limit_min, least_flight_min=least_min)
    if not result.routes:
        return result
    minutes = [route_minutes(scenario, r) for r in result.routes]
    if max(minutes) <= limit_min:
        result.statement += (
            f"; every front route flies within the endurance of {limit_min:g} min in the design "
            f"wind (the longest {_minutes_text(max(minutes))}), so this is the front within it"
        )
        return result
    within = [r for r, m in zip(result.routes, minutes) if m <= limit_min]
    timed = timed_front(
        scenario, limit_s, use_probability, max_corrections, max_labels, to_b, time_limit, within
    )
    result.stats["endurance_labels"] = timed.labels
    if not timed.routes:
        if not timed.exhausted:
            why = (
                f"no route within the endurance of {limit_min:g} min found before the search's "
                f"budget ({_budget_text(max_labels, time_limit)}) ended it, so infeasibility is "
                "not proven"
            )
            return EngineResult([], [], False, why, result.stats)
        why = (
            f"no route within the endurance of {limit_min:g} min (exhaustive search of the "
            f"routes within it): the quickest route of the front needs "
            f"{_minutes_text(min(minutes))} of flight in the design wind, and no route needs "
            f"less than {_minutes_text(least_min)}"
        )
        return EngineResult([], [], True, why, result.stats)
    routes = [_flown(scenario, points) for *_, points in timed.routes]
    if timed.exhausted:
        beyond = sum(m > limit_min for m in minutes)
        statement = (
            f"exact: the Pareto front within the endurance of {limit_min:g} min in the design "
            f"wind, proven by a search of the routes within it ({timed.labels} labels; flight "
            "time a resource along the route, bounded below by the least chord time to B; "
            f"{beyond} route(s) of the front of all routes fly longer)"
        )
        return EngineResult(routes, [r.length for r in routes], True, statement, result.stats)
    statement = (
        f"not proven: the routes found within the endurance of {limit_min:g} min before the "
        f"search's budget ({_budget_text(max_labels, time_limit)}) ended it; each route's "
        "lower bound is the front's of all routes"
    )
    floors = [_floor(r, result, use_probability) for r in routes]
    # Routes with no more corrections (or a higher probability) may still be missing.
    unsettled = [False] * len(routes)
    return EngineResult(routes, floors, False, statement, result.stats, unsettled)


def _floor(route: Route, unlimited: EngineResult, probability: bool) -> float:
    """A lower bound of the shortest route within the endurance with no more corrections than
    ``route`` (nor less probability): the shortest such of all routes, from their proven
    front (0 when it is not proven)."""
    if not unlimited.optimal:
        return 0.0
    return min(
        (
            r.length
            for r in unlimited.routes
            if r.corrections <= route.corrections
            and (not probability or r.probability >= route.probability - PROB_EPS)
        ),
        default=0.0,
    )


def _flown(scenario: Scenario, points: tuple[int, ...]) -> Route:
    """The route through ``points`` flown again, with its exact success probability."""
    route = flown_route(scenario, points)
    legs = [s.leg for s in route.stops[1:]]
    sp = success_probability(scenario, route.points, legs)
    return route.with_probabilities(sp.probability, sp.per_stop)


def _minutes_text(minutes: float) -> str:
    """Minutes as the plan says them: '378 min (6.3 h)'."""
    if not math.isfinite(minutes):
        return "forever (the design wind is at least the airspeed)"
    return f"{minutes:.0f} min ({minutes / 60:.1f} h)" if minutes >= 90 else f"{minutes:.1f} min"


def _budget_text(max_labels: int | None, time_limit: float | None) -> str:
    """The search's budget in words."""
    labels = "no label limit" if max_labels is None else f"{max_labels:,} labels"
    seconds = "no time limit" if time_limit is None else f"{time_limit:g} s"
    return f"{labels}, {seconds}"
