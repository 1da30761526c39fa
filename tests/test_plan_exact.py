"""``plan()`` is exact in every leg model and objective set: its front equals enumeration.

Each scenario is tiny (3 to 6 correction points) and tall (altitudes spread over 15 % of its
length: 4.5 to 7 km), so that climb and descent limits rule legs out or make them longer: with
R = 0 a leg steeper than the limit cannot be flown at all (there is no helix of radius 0), with
turns it is flown with a helix. The reference enumerates every simple route, flies it with the
project's own route evaluation (``bnb.flown_route``, under the scenario's leg model, limits
included) and the exact probability model, and keeps the Pareto fronts (``test_bnb``'s
enumeration, each route flown once for both objective sets). cs3d plans without climb limits by
definition (docs/model.md): with limits set its front must not change.
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np
import pytest
from helpers import contest_params
from test_bnb import all_routes, pareto

from gcs_planner.core.bnb import flown_route
from gcs_planner.core.planner import plan
from gcs_planner.core.probability import success_probability
from gcs_planner.core.search import straight_front
from gcs_planner.errors import InfeasibleError
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Scenario

TWO = ("length", "corrections")
THREE = ("length", "corrections", "probability")
# (leg model, turning radius): R = 0 is straight legs whatever the model name.
MODELS = [("airplane", 0.0), ("airplane", 400.0), ("cs3d", 400.0)]
# Seeds per model: enumeration flies every route (about 1 ms a leg with turns), so the sample
# is larger where it is cheap and where the wrong optimum was (R = 0).
SEEDS = {0.0: range(32), 400.0: range(16)}


def tall_scenario(seed: int, leg_model: str, radius: float, limited: bool) -> Scenario:
    """4 or 5 correction points (6 for every twelfth seed with R = 0: 1,957 routes), half
    unreliable, in a corridor 30 to 45 km long with dataset 1's limits (so that most routes
    need a V and an H correction), altitudes spread over 15 % of its length, A at one end of
    that range; climb and descent limits of 5 to 25 degrees when ``limited`` (the same
    points either way)."""
    rng = np.random.default_rng(seed)
    climb, descent = rng.uniform(5.0, 25.0, 2)
    if not limited:
        climb = descent = 90.0
    params = contest_params(
        turn_radius=radius,
        fail_residual=float(rng.uniform(2, 15)),
        max_climb_angle=float(climb),
        max_descent_angle=float(descent),
    )
    length = float(rng.uniform(30_000, 45_000))
    n = 6 if radius == 0 and seed % 12 == 5 else int(rng.integers(4, 6))
    box = (length, length * rng.uniform(0.05, 0.2), 1.0)
    flat = random_scenario(n, seed, params=params, box=box, unreliable_fraction=0.5)
    xyz = flat.xyz.copy()
    xyz[:, 2] = rng.uniform(0.0, 0.15 * length, len(xyz))
    xyz[0, 2] = 0.0
    if rng.random() < 0.5:  # a descent overall as often as a climb
        xyz[:, 2] = xyz[::-1, 2]
    return replace(flat, xyz=xyz).with_vehicle(leg_model=leg_model)


@cache
def enumerated(seed: int, leg_model: str, radius: float, limited: bool) -> dict:
    """Both enumerated fronts of a scenario, by objective set, as (length, corrections,
    -probability) tuples (probability 0 for two objectives): every simple route flown once.
    A route with any chance to arrive is one that arrives when every correction succeeds
    (``seeding``), so the two-objective routes are those with probability above 0."""
    return enumerate_fronts(tall_scenario(seed, leg_model, radius, limited))


def enumerate_fronts(scenario: Scenario) -> dict:
    """``enumerated``'s two fronts of any scenario: every simple route flown once."""
    two, three = [], []
    for points in all_routes(scenario):
        route = flown_route(scenario, points)
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
        assert_same(planned_front(scenario, objectives), want[objectives], f"{what}, {objectives}")
    return want


def assert_same(got: list[tuple], want: list[tuple], what: str) -> None:
    assert [g[1:] for g in got] == [w[1:] for w in want], (what, got, want)
    np.testing.assert_allclose(
        [g[0] for g in got], [w[0] for w in want], rtol=1e-6, atol=0, err_msg=what
    )


@pytest.mark.parametrize(("leg_model", "radius"), MODELS, ids=["straight", "airplane", "cs3d"])
def test_plan_equals_enumeration(leg_model: str, radius: float) -> None:
    seeds = SEEDS[radius]
    nonempty = bitten = 0
    for seed in seeds:
        for limited in (False, True):
            scenario = tall_scenario(seed, leg_model, radius, limited)
            want = assert_plans_enumeration(scenario, f"seed {seed}, {limited=}")
            nonempty += bool(want[TWO])
        bitten += enumerated(seed, leg_model, radius, False) != want
    assert nonempty >= len(seeds) // 4
    if leg_model == "cs3d":
        assert bitten == 0  # cs3d legs plan without climb limits
    else:
        assert bitten >= len(seeds) // 4, "the limits must change the front in the sample"


@pytest.mark.parametrize("compiled", [False, True], ids=["numpy", "compiled"])
def test_straight_search_sees_the_climb_limits(compiled: bool) -> None:
    """Both engines of the straight label search (plan() takes the compiled one on large maps)
    complete routes only along legs the limits allow: a too-steep last leg is no arc."""
    for seed in SEEDS[0.0]:
        scenario = tall_scenario(seed, "airplane", 0.0, limited=True)
        result = straight_front(scenario, compiled=compiled)
        got = sorted(((fp.length, fp.corrections, 0.0) for fp in result.front), key=lambda t: t[1])
        assert_same(got, enumerated(seed, "airplane", 0.0, True)[TWO], f"seed {seed}")
