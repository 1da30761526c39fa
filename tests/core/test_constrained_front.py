"""Both constraints the engines do not carry at once (core/constrained_front.py): the endurance
in a design wind and the captures in a design turbulence. The planner's front equals
enumeration's with both conditions: brute force (``baselines/brute.py``, its own arithmetic)
for straight legs, every simple route flown for turns and the probability objective. The
search spends the plan's one budget and says which limit stopped it."""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable

import numpy as np
import pytest
from support.enumeration import THREE, TWO, all_routes, pareto
from support.prefix_flight import PrefixFlights
from support.scenarios import turning_scenario, uncertain_straight_scenario, windy_envelope

from gcs_planner.baselines.brute import brute_force_front
from gcs_planner.core.bnb import flown_leg, flown_route_legs
from gcs_planner.core.capture_front import route_fits
from gcs_planner.core.flight_time import route_minutes
from gcs_planner.core.planner import plan
from gcs_planner.core.probability import success_probability
from gcs_planner.core.route import Leg, Route, evaluate_route
from gcs_planner.errors import InfeasibleError
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario


def _windy_turbulent(base: Scenario, seed: int, radius: float, top: float = 1.5) -> Scenario:
    """``base`` at 0.1 m an error unit, capture radius ``radius``, vertical allowances up to
    ``top`` m, in a design wind of 0.5 to 0.9 of the airspeed from a drawn direction."""
    rng = np.random.default_rng(7_000 + seed)
    vertical = tuple(
        0.0 if Kind(int(k)) == Kind.A else float(rng.uniform(0.0, top)) for k in base.kind
    )
    envelope = windy_envelope(rng, float(base.xyz[:, 2].max()))
    return dataclasses.replace(
        base, error_unit=0.1, capture_radius=radius, capture_vertical=vertical, envelope=envelope
    )


def _routes(
    sc: Scenario, probability: bool, fly: Callable[[tuple[int, ...]], Route] | None = None
) -> list[tuple]:
    """Every simple route flown (by ``fly``, when given) that arrives (or is feasible):
    (length, k, -p, minutes, fits)."""
    out = []
    fly = fly or _straight_flight(sc) or PrefixFlights(sc).route
    for pts in all_routes(sc):
        route = fly(pts)
        if probability:
            legs = [s.leg for s in route.stops[1:]]
            p = success_probability(sc, pts, legs).probability
        if (p > 0) if probability else route.feasible:
            mass = round(-p, 12) if probability else 0.0
            minutes = route_minutes(sc, route)
            fits = route_fits(sc, route)
            out.append((round(route.length, 6), route.corrections, mass, minutes, fits))
    return out


def _straight_flight(sc: Scenario) -> Callable[[tuple[int, ...]], Route] | None:
    """``flown_route`` of the scenario's routes, for straight legs from a free heading at A (None
    otherwise): each leg flown as ``route_trajectory`` flies it (the first from the chord, the
    next from the heading the one before ended with: a straight leg's is its chord's), once per
    (point before, start, end) for every route through them, then ``evaluate_route``."""
    model = scenario_leg_model(sc)
    if model.carries_heading or sc.heading_at_a is not None:
        return None
    xyz, memo = sc.xyz, {}

    def leg(before: int | None, a: int, b: int) -> tuple[Leg, object]:
        key = (before, a, b)
        if key not in memo:
            if before is None:
                flown = flown_route_legs(sc, (a, b))[0]
            else:
                flown = model.leg(xyz[a], leg(None, before, a)[1], xyz[b])
            memo[key] = (flown_leg(flown), flown.heading_out)
        return memo[key]

    def fly(pts: tuple[int, ...]) -> Route:
        legs = [leg(None, pts[0], pts[1])[0]]
        legs += [leg(pts[k - 1], pts[k], pts[k + 1])[0] for k in range(1, len(pts) - 1)]
        return evaluate_route(sc, pts, legs, turn_radius=sc.params.turn_radius)

    return fly


def _within(routes: list[tuple], minutes: float, fit: bool) -> list[tuple]:
    return pareto([r[:3] for r in routes if r[3] <= minutes and (r[4] or not fit)])


def _planned(sc: Scenario, objectives: tuple[str, ...]) -> list[tuple]:
    probability = "probability" in objectives
    try:
        result = plan(sc, objectives=objectives, max_labels=None, time_limit=None)
    except InfeasibleError as err:
        assert "not proven" not in str(err), str(err)
        return []
    assert result.optimal, result.statement
    for route in result.routes:
        assert route_fits(sc, route) and route_minutes(sc, route) <= sc.endurance
    got = [
        (round(r.length, 6), r.corrections, round(-r.probability, 12) if probability else 0.0)
        for r in result.routes
    ]
    return sorted(got, key=lambda t: (t[1], t[0], t[2]))


def _assert_same(got: list[tuple], want: list[tuple], context: object) -> None:
    assert [g[1:] for g in got] == [w[1:] for w in want], (context, got, want)
    np.testing.assert_allclose([g[0] for g in got], [w[0] for w in want], atol=1e-6)


def _endurance(routes: list[tuple], seed: int) -> float | None:
    """An endurance between the quickest fitting route and the slowest route of the front of
    the fitting routes, so that it often cuts that front (None: no route fits)."""
    fit = [r for r in routes if r[4] and math.isfinite(r[3])]
    if not fit:
        return None
    front = _within(routes, math.inf, fit=True)
    quickest = min(r[3] for r in fit)
    slowest = max([r[3] for r in fit if r[:3] in front], default=quickest)
    return float(np.random.default_rng(seed).uniform(quickest, max(quickest, slowest)))


def test_both_constraints_at_once_equal_brute_force_on_straight_legs():
    """240 straight-leg scenarios with unreliable points, allowances up to 0.5 m: the planner's
    (length, corrections) front within the endurance and fitting every capture equals brute
    force's with both; in the sample the two together give fronts neither alone does."""
    compared = both_bite = 0
    for seed in range(240):
        base = uncertain_straight_scenario(seed)
        sc = _windy_turbulent(base, seed, 3.0 + 0.5 * (seed % 3), top=0.5)
        routes = _routes(sc, False)
        minutes = _endurance(routes, seed)
        if minutes is None:
            continue
        sc = dataclasses.replace(sc, endurance=minutes)
        want = [(round(length, 6), k, 0.0) for length, k, _ in brute_force_front(sc)]
        # Brute force's own arithmetic agrees with every route flown and checked.
        _assert_same(want, _within(routes, minutes, fit=True), ("brute", seed))
        _assert_same(_planned(sc, TWO), want, seed)
        compared += 1
        time_only = _within(routes, minutes, fit=False)
        fit_only = _within(routes, math.inf, fit=True)
        both_bite += want != time_only and want != fit_only
    assert compared >= 60 and both_bite >= 3, (compared, both_bite)


@pytest.mark.parametrize("seed", range(30))
def test_both_constraints_with_turns_and_probability_equal_enumeration(seed):
    sc = _windy_turbulent(turning_scenario(seed, 200.0, max_points=4), seed, 4.0)
    fly = functools.cache(PrefixFlights(sc).route)  # each route flown once for both
    for objectives in (TWO, THREE):
        routes = _routes(sc, "probability" in objectives, fly)
        minutes = _endurance(routes, seed)
        if minutes is None:
            continue
        timed = dataclasses.replace(sc, endurance=minutes)
        _assert_same(_planned(timed, objectives), _within(routes, minutes, fit=True), seed)


def _binding() -> Scenario:
    """A straight-leg scenario of the sample whose front of all routes breaks a constraint (so
    the constrained search runs) and that has a route keeping to both."""
    for seed in range(240):
        sc = _windy_turbulent(uncertain_straight_scenario(seed), seed, 3.5)
        routes = _routes(sc, False)
        minutes = _endurance(routes, seed)
        if minutes is None:
            continue
        if _within(routes, minutes, fit=True) != _within(routes, math.inf, fit=False):
            return dataclasses.replace(sc, endurance=minutes)
    raise AssertionError("no scenario of the sample binds")


def test_no_cpu_time_stops_the_constrained_search_before_its_first_label_and_says_so():
    """A time limit of 0 s stops the search before its first label whatever the machine (the
    straight-leg engine spends no budget): not proven, the CPU time limit named."""
    sc = _binding()
    with pytest.raises(InfeasibleError, match="stopped by the 0 s CPU time limit") as err:
        plan(sc, objectives=TWO, time_limit=0.0)
    assert "not proven" in str(err.value)


def test_the_label_limit_stops_the_constrained_search_and_says_so():
    sc = _binding()
    try:
        result = plan(sc, objectives=TWO, max_labels=1, time_limit=None)
    except InfeasibleError as err:
        text = str(err)
    else:
        assert not result.optimal and not any(result.proven())
        text = result.statement
    assert "not proven" in text and "stopped by the limit of 1 labels per search" in text
    assert "raise --max-labels" in text
