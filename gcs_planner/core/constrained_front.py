"""The exact front of the routes that keep to constraints the label-setting search does not carry
(the endurance, core/endurance_front.py; the captures in a design turbulence,
core/capture_front.py): one proof and one search for all of them.

Each constraint depends only on the route up to a point, and a prefix that breaks it has no
completion that keeps to it, so ``within_constraints`` proves the constrained front in three
steps, each exact:

1. A constraint no route can keep (its ``refusal``) means no route: said as the reason.
2. The front of every route (the engines') is the constrained front when each of its routes
   keeps to every constraint: every route that keeps to them is matched or beaten by a front
   route, which keeps to them too.
3. Otherwise ``constrained_front`` searches the routes that keep to them: depth first over
   simple routes, no dominance among partial routes (a dominating one may have taken longer or
   carry an error outcome that misses a capture), a partial route dropped when a constraint
   refuses its last leg (each constraint's ``admits`` with its lower bound to B), when no error
   state survives it, or when a route found matches or beats every completion of it (its length
   plus the chord to B, its corrections, its probability). It spends the plan's budget
   (core/budget.py): its own labels, the plan's CPU seconds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from gcs_planner.core.bnb import flown_route
from gcs_planner.core.budget import Budget
from gcs_planner.core.engines import EngineResult
from gcs_planner.core.probability import PROB_EPS, State, propagate, success_probability
from gcs_planner.core.reach import arrival_limits_m
from gcs_planner.core.route import Route
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

# Lengths within this many metres are the same length (as the planner's front).
_LENGTH_TIE_M = 1e-6


@dataclass(frozen=True)
class Leg:
    """A leg the search weighs: from point ``origin`` to ``target``, ``flown`` metres, and the
    error states arriving at ``target`` within its limits (metres flown since each reset, over
    every correction outcome the constraints judge)."""

    origin: int
    target: int
    flown: float
    arrived: tuple[State, ...]


class RouteConstraint(Protocol):
    """A condition on the route up to each point that a prefix breaking it cannot recover."""

    # Whether the constraint judges captures over every correction outcome (then the search
    # carries them all, even without the probability objective).
    every_outcome: bool
    # Its figures for the plan's stats (``Plan.stats``).
    figures: dict[str, float]

    def passable(self, point: int) -> bool:
        """Whether any route may pass ``point`` (judged once, before the search)."""

    def admits(self, leg: Leg, carried: float) -> float | None:
        """What the constraint carries to ``leg.target`` (e.g. seconds flown) from ``carried``
        at its origin (0 at A), or None when no completion of the prefix through this leg can
        keep to it (its lower bound to B included)."""

    def route_keeps(self, route: Route) -> bool:
        """Whether a whole planned route keeps to it."""

    def refusal(self) -> str | None:
        """Why no route can keep to it, found before any search (None: it may)."""

    def phrase(self) -> str:
        """The routes it allows, in words ("within the endurance of 60 min")."""

    def front_keeps(self, routes: Sequence[Route]) -> str:
        """Said when every route of the front of all routes keeps to it."""

    def why_none(self, routes: Sequence[Route]) -> str:
        """Why no route keeps to it, given the front of all routes (an exhaustive search)."""


@dataclass
class ConstrainedFront:
    """What ``constrained_front`` found: (length, corrections, probability, points) per front
    route, whether the search ran to the end, and how many partial routes it extended."""

    routes: list[tuple[float, int, float, tuple[int, ...]]]
    exhausted: bool
    labels: int


def covers(a: tuple, b: tuple, probability: bool) -> bool:
    """Route values ``a`` (length, k, mass) match or beat ``b``'s in every objective."""
    return (
        a[0] <= b[0] + _LENGTH_TIE_M
        and a[1] <= b[1]
        and (not probability or a[2] >= b[2] - PROB_EPS)
    )


def constrained_front(
    scenario: Scenario,
    constraints: Sequence[RouteConstraint],
    probability: bool,
    max_corrections: int | None,
    budget: Budget,
    seeds: Sequence[Route] = (),
) -> ConstrainedFront:
    """The exact Pareto front of (length, corrections[, probability]) over the simple routes
    that keep to every one of ``constraints`` (step 3 of the module's proof), within
    ``budget`` (else not exhausted). ``seeds``: routes known to keep to them (the engine's),
    found from the start so that they prune at once."""
    model = scenario_leg_model(scenario)
    xyz, params, n, end = scenario.xyz, scenario.params, scenario.n, scenario.end
    kind = [Kind(int(c)) for c in scenario.kind]
    every = probability or any(c.every_outcome for c in constraints)
    unreliable = scenario.unreliable if every else np.zeros(n, dtype=bool)
    kmax = n if max_corrections is None else max_corrections
    chord_to_b = np.linalg.norm(xyz - xyz[end], axis=1)
    lim_v, lim_h = arrival_limits_m(scenario)
    usable = np.array([all(c.passable(t) for c in constraints) for t in range(n)])
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a)
    found: list[tuple[float, int, float, tuple[int, ...]]] = []
    stopped = False

    def covered(length: float, k: int, mass: float) -> bool:
        return any(covers(f, (length, k, mass), probability) for f in found)

    def offer(values: tuple[float, int, float, tuple[int, ...]]) -> None:
        if not covered(values[0], values[1], values[2]):
            found[:] = [f for f in found if not covers(values, f, probability)]
            found.append(values)

    def extend(path: tuple[int, ...], heading, length: float, carried, states, sure) -> None:  # noqa: ANN001
        nonlocal stopped
        if not budget.take():
            stopped = True
            return
        if budget.due():  # depth first: no length below which the front is complete yet
            budget.report(budget.spent, len(path), len(found), 0.0)
        i, k = path[-1], len(path) - 1
        # A leg is at least its chord: the points no error state can reach within the limits.
        v_min, h_min = min(v for v, _ in states), min(h for _, h in states)
        chord = np.linalg.norm(xyz - xyz[i], axis=1)
        near = usable & (v_min + chord <= lim_v) & (h_min + chord <= lim_h)
        options = []
        for t in np.flatnonzero(near).tolist():
            if t in path or (t != end and k + 1 > kmax):
                continue
            leg = model.leg(xyz[i], heading, xyz[t])
            if not np.isfinite(leg.length):
                continue
            options.append((length + leg.length + chord_to_b[t], t, leg))
        for _, t, leg in sorted(options, key=lambda o: o[0]):
            top_v, top_h = params.limits_m(kind[t])
            arrived = [(v + leg.length, h + leg.length) for v, h in states]
            arrived = tuple((v, h) for v, h in arrived if v <= top_v and h <= top_h)
            if not arrived:
                continue
            step = Leg(i, t, leg.length, arrived)
            after_carried = tuple(c.admits(step, v) for c, v in zip(constraints, carried))
            if None in after_carried:
                continue
            # Without the probability objective a route is feasible on its all-success path;
            # the other outcomes are carried only for the constraints that judge them.
            after, _ = propagate(states, leg.length, kind[t], bool(unreliable[t]), params)
            now, _ = propagate(sure, leg.length, kind[t], False, params) if every else (after, 0)
            if not after or not (probability or now):
                continue
            mass = min(1.0, sum(after.values())) if probability else 1.0
            nl = length + leg.length
            if t == end:
                offer((nl, k, mass, (*path, t)))
                continue
            if covered(nl + chord_to_b[t], k + 1, mass):
                continue
            extend((*path, t), leg.heading_out, nl, after_carried, after, now)
            if stopped:
                return

    for route in seeds:
        offer((route.length, route.corrections, route.probability if probability else 1.0,
               tuple(route.points)))  # fmt: skip
    first = {scenario.initial_errors: 1.0}
    if usable[end]:
        extend((scenario.start,), heading_a, 0.0, (0.0,) * len(constraints), first, dict(first))
    found.sort(key=lambda f: (f[1], f[0]))
    return ConstrainedFront(found, not stopped, budget.spent)


def within_constraints(
    scenario: Scenario,
    run_engine: Callable[[], EngineResult],
    constraints: Sequence[RouteConstraint],
    use_probability: bool,
    max_corrections: int | None,
    budget: Budget,
) -> EngineResult:
    """The engine's result restricted to the routes that keep to every one of ``constraints``
    (the module's three steps), the search within ``budget``, the plan's; with no route, its
    statement says which constraint is why."""
    figures = {k: v for c in constraints for k, v in c.figures.items()}
    for constraint in constraints:
        why = constraint.refusal()
        if why is not None:
            return EngineResult([], [], True, why, figures)
    result = run_engine()
    result.stats.update(figures)
    if not result.routes:
        return result
    keeps = [all(c.route_keeps(r) for c in constraints) for r in result.routes]
    if all(keeps):
        result.statement += "".join(c.front_keeps(result.routes) for c in constraints)
        return result
    what = " and ".join(c.phrase() for c in constraints)
    within = [r for r, ok in zip(result.routes, keeps) if ok]
    search = budget.share(1.0, stage="constrained front")
    found = constrained_front(
        scenario, constraints, use_probability, max_corrections, search, within
    )
    result.stats["constrained_labels"] = found.labels
    if not found.routes:
        if not found.exhausted:
            why = (
                f"no route {what} found before the search's budget ({search.describe()}) ended "
                f"it, so infeasibility is not proven: {search.advice()}"
            )
            return EngineResult([], [], False, why, result.stats)
        reasons = "; ".join(c.why_none(result.routes) for c in constraints)
        why = f"no route {what} (exhaustive search of them): {reasons}"
        return EngineResult([], [], True, why, result.stats)
    routes = [flown_again(scenario, points) for *_, points in found.routes]
    if found.exhausted:
        statement = (
            f"exact: the Pareto front of the routes {what}, proven by a search of them "
            f"({found.labels} labels; {keeps.count(False)} route(s) of the front of all routes "
            "break a constraint)"
        )
        return EngineResult(routes, [r.length for r in routes], True, statement, result.stats)
    statement = (
        f"not proven: the routes {what} found before the search's budget ({search.describe()}) "
        f"ended it ({search.advice()}); each route's lower bound is the front's of all routes"
    )
    floors = [_floor(r, result, use_probability) for r in routes]
    # Routes with no more corrections (or a higher probability) may still be missing.
    return EngineResult(routes, floors, False, statement, result.stats, [False] * len(routes))


def _floor(route: Route, unlimited: EngineResult, probability: bool) -> float:
    """A lower bound of the shortest constrained route with no more corrections than ``route``
    (nor less probability): the shortest such of all routes, from their proven front (0 when
    it is not proven)."""
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


def flown_again(scenario: Scenario, points: tuple[int, ...]) -> Route:
    """The route through ``points`` flown again, with its exact success probability."""
    route = flown_route(scenario, points)
    legs = [s.leg for s in route.stops[1:]]
    sp = success_probability(scenario, route.points, legs)
    return route.with_probabilities(sp.probability, sp.per_stop)
