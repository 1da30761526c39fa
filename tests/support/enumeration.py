"""Reference fronts by brute force: every simple route enumerated (or walked depth first) and
flown with the project's own route evaluation and the exact probability model, the Pareto
front kept by plain pairwise comparison; and the assertions that a search's front equals one."""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Iterable, Iterator

import numpy as np

from gcs_planner.core.bnb import Options, bnb_front, flown_route
from gcs_planner.core.planner import plan
from gcs_planner.core.probability import propagate, success_probability
from gcs_planner.core.route import Route
from gcs_planner.errors import InfeasibleError
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

from .scenarios import probed_scenario
from .shared_results import shared_front

TWO = ("length", "corrections")
THREE = ("length", "corrections", "probability")


def all_routes(scenario: Scenario) -> Iterator[tuple[int, ...]]:
    """Every simple route from A to B, shortest chains first."""
    inner = [i for i in range(scenario.n) if i not in (scenario.start, scenario.end)]
    for k in range(len(inner) + 1):
        for chain in itertools.permutations(inner, k):
            yield (scenario.start, *chain, scenario.end)


def pareto(points: list[tuple]) -> list[tuple]:
    """Non-dominated (length, corrections, -probability) tuples, by plain pairwise comparison."""
    keep = []
    for a in points:
        dominated = any(
            all(x <= y for x, y in zip(b, a)) and any(x < y for x, y in zip(b, a)) for b in points
        )
        if not dominated and a not in keep:
            keep.append(a)
    return sorted(keep, key=lambda t: (t[1], t[0], t[2]))


def enumerate_front(
    scenario: Scenario,
    probability: bool,
    keep: Callable[[Route], bool] | None = None,
    flights: Iterable[tuple[tuple[int, ...], Route]] | None = None,
) -> list[tuple]:
    """The front of every simple route, each flown under the scenario's leg model (only the
    routes ``keep`` admits, when given; ``flights``: (points, flown route) of every simple
    route, when the caller flies them its own way)."""
    if flights is None:
        flights = ((pts, flown_route(scenario, pts)) for pts in all_routes(scenario))
    values = []
    for pts, route in flights:
        if keep is not None and not keep(route):
            continue
        if probability:
            legs = [s.leg for s in route.stops[1:]]
            p = success_probability(scenario, pts, legs).probability
            if p > 0:
                values.append((round(route.length, 6), route.corrections, round(-p, 12)))
        elif route.feasible:
            values.append((round(route.length, 6), route.corrections, 0.0))
    return pareto(values)


def assert_front_equals_enumeration(
    scenario: Scenario,
    probability: bool,
    seed: object,
    options: Options | None = None,
    want: list[tuple] | None = None,
) -> tuple:
    """The branch and bound's front, proven, equal to enumeration of every simple route
    (``want``, when the caller enumerated it already); returns (the search's result, the
    enumerated front). ``seed`` names the case in a failure."""
    result = bnb_front(scenario, probability=probability, max_labels=10**6, options=options)
    assert result.optimal, seed
    got = [
        (round(f.length, 6), f.corrections, round(-f.probability, 12) if probability else 0.0)
        for f in result.front
    ]
    if want is None:
        want = enumerate_front(scenario, probability)
    assert [g[1:] for g in got] == [w[1:] for w in want], seed
    np.testing.assert_allclose(
        [g[0] for g in got], [w[0] for w in want], atol=1e-6, err_msg=str(seed)
    )
    return result, want


def enumerate_straight_front(scenario: Scenario) -> list[tuple]:
    """Every simple route with straight legs: length from the coordinates, probability from the
    exact chain (0 when the route cannot arrive)."""
    xyz = scenario.xyz
    values = []
    for pts in all_routes(scenario):
        p = success_probability(scenario, pts).probability
        if p > 0:
            length = float(np.linalg.norm(np.diff(xyz[list(pts)], axis=0), axis=1).sum())
            values.append((round(length, 6), len(pts) - 2, round(-p, 12)))
    return pareto(values)


def enumerate_fronts(
    scenario: Scenario, flights: Iterable[tuple[tuple[int, ...], Route]] | None = None
) -> dict:
    """Both enumerated fronts of a scenario, by objective set (TWO, THREE), as (length,
    corrections, -probability) tuples (probability 0 for two objectives): every simple route
    flown once (``flights``: (points, flown route) of every simple route, when the caller flies
    them its own way)."""
    if flights is None:
        flights = ((points, flown_route(scenario, points)) for points in all_routes(scenario))
    two, three = [], []
    for points, route in flights:
        if not route.feasible:
            continue
        legs = [s.leg for s in route.stops[1:]]
        p = success_probability(scenario, points, legs).probability
        assert p > 0, points
        two.append((round(route.length, 6), route.corrections, 0.0))
        three.append((round(route.length, 6), route.corrections, round(-p, 12)))
    return {TWO: pareto(two), THREE: pareto(three)}


def planned_front(scenario: Scenario, objectives: tuple[str, ...]) -> list[tuple]:
    """``plan()``'s front as enumerate_front's (length, corrections, -probability) tuples."""
    probability = "probability" in objectives
    try:
        result = plan(scenario, objectives=objectives, max_labels=None, time_limit=None)
    except InfeasibleError:
        return []
    assert result.optimal
    if scenario.leg_model == "airplane":
        # Every route the aircraft is given can be flown within its limits.
        assert not any("steeper" in w for w in result.warnings), result.warnings
    for route in result.routes:
        assert route.feasible and route.simple, route.points
    got = [
        (r.length, r.corrections, round(-r.probability, 12) if probability else 0.0)
        for r in result.routes
    ]
    return sorted(got, key=lambda t: (t[1], t[0], t[2]))


def assert_plans_enumeration(scenario: Scenario, what: str) -> dict:
    """The planner's fronts for two and three objectives equal enumeration's; those fronts."""
    want = enumerate_fronts(scenario)
    for objectives in (TWO, THREE):
        assert_fronts_close(
            planned_front(scenario, objectives), want[objectives], f"{what}, {objectives}"
        )
    return want


def assert_fronts_close(got: list[tuple], want: list[tuple], what: str) -> None:
    """The same corrections and probabilities, lengths within a relative 1e-6."""
    assert [g[1:] for g in got] == [w[1:] for w in want], (what, got, want)
    np.testing.assert_allclose(
        [g[0] for g in got], [w[0] for w in want], rtol=1e-6, atol=0, err_msg=what
    )


def dfs_front(scenario: Scenario, probability: bool) -> list[tuple[float, int, float]]:
    """The Pareto front of (length, corrections, -probability) over every simple route, each
    leg flown from the heading the previous one ended with (sorted like ``enumerate_front``).

    Every simple route is walked depth first, a prefix dropped only when no error branch
    survives it (every extension of it is then infeasible too): so scenarios of nine to
    fourteen points, too many for enumerating every permutation, can be checked."""
    model = scenario_leg_model(scenario)
    xyz, params, n = scenario.xyz, scenario.params, scenario.n
    kind = [Kind(int(c)) for c in scenario.kind]
    unreliable = scenario.unreliable if probability else np.zeros(n, dtype=bool)
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a)
    values = []

    def extend(path, heading, length, states) -> None:  # noqa: ANN001 - the walk's state
        for t in range(n):
            if t in path:
                continue
            leg = model.leg(xyz[path[-1]], heading, xyz[t])
            if not np.isfinite(leg.length):
                continue
            after, _ = propagate(states, leg.length, kind[t], bool(unreliable[t]), params)
            if not after:
                continue
            if t == scenario.end:
                p = min(1.0, sum(after.values())) if probability else 1.0
                values.append((round(length + leg.length, 6), len(path) - 1, round(-p, 12)))
            else:
                extend((*path, t), leg.heading_out, length + leg.length, after)

    extend((scenario.start,), heading_a, 0.0, {(0.0, 0.0): 1.0})
    return walked_front(values, probability)


def walked_front(
    values: list[tuple[float, int, float]], probability: bool
) -> list[tuple[float, int, float]]:
    """The Pareto front of the (length, corrections, -probability) of every route walked,
    sorted by corrections, then length (``dfs_front``'s order)."""
    front: list[tuple[float, int, float]] = []
    for v in sorted(set(values)):  # by length: only an earlier value can dominate a later one
        if not any(all(x <= y for x, y in zip(kept, v)) for kept in front):
            front.append(v)
    if not probability:
        front = [(length, k, 0.0) for length, k, _ in front]
    return sorted(front, key=lambda t: (t[1], t[0], t[2]))


@functools.cache
def probed_front(seed: int, legs: str, probability: bool) -> list[tuple[float, int, float]]:
    """``dfs_front`` of ``probed_scenario(seed, legs)``, enumerated once per test session (the
    tests of the probes and of the compiled searches ask for the same scenarios), and shared
    with the run's other test processes (support/shared_results.py). Walked with the onward
    legs fanned (support/fan_walk.py, held equal to ``dfs_front`` in test_fan_walk.py)."""
    from .fan_walk import fanned_dfs_front  # (fan_walk walks with dfs_front: imported late)

    question = (seed, legs, probability)
    return shared_front(
        "probed_front",
        question,
        lambda: fanned_dfs_front(probed_scenario(seed, legs), probability),
    )


def front_of(result, probability: bool) -> list[tuple[float, int, float]]:  # noqa: ANN001
    """A search's front as (length, corrections, -probability) tuples (probability 0 for two
    objectives)."""
    return [
        (round(f.length, 6), f.corrections, round(-f.probability, 12) if probability else 0.0)
        for f in result.front
    ]


def assert_same_front(got: list[tuple], want: list[tuple], seed: object) -> None:
    """The same corrections and probabilities, lengths within 1e-6 m."""
    assert [g[1:] for g in got] == [w[1:] for w in want], seed
    np.testing.assert_allclose([g[0] for g in got], [w[0] for w in want], atol=1e-6)
