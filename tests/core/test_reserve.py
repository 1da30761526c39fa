"""The flight reserve: a plan that keeps every error within its limit for a flight up to
``reserve`` metres longer than planned between two resets of that error."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from support.prefix_fronts import assert_front_equals_prefix_enumeration
from support.scenarios import climbing_scenario

from gcs_planner.core.bnb import bnb_front, flown_route
from gcs_planner.core.probability import success_probability
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import PARAMETER_NAMES, Parameters

LIMIT_NAMES = PARAMETER_NAMES[:5]


def tight_scenario(seed: int):
    """The climbing scenarios of support/scenarios.py (turns, helices, unreliable points) with
    their limits scaled down, so that the limits, and with them the reserve, decide the front.
    At most 4 correction points (65 routes to enumerate, not 326): the reserve changes as many
    fronts of the sample (7 of 40) as with 5."""
    base = climbing_scenario(seed, max_points=4)
    scale = float(np.random.default_rng(500 + seed).uniform(0.5, 0.9))
    p = base.params
    tighter = {k: getattr(p, k) * scale for k in LIMIT_NAMES}
    return dataclasses.replace(base, params=dataclasses.replace(p, **tighter))


def with_reserve(scenario, reserve: float):
    return dataclasses.replace(
        scenario, params=dataclasses.replace(scenario.params, reserve=reserve)
    )


def with_tighter_limits(scenario, reserve: float):
    """The same scenario without a reserve, every limit lowered by what the reserve's metres
    would add to the error: an independent statement of what the reserve means."""
    p = scenario.params
    tighter = {k: getattr(p, k) - reserve * p.delta for k in LIMIT_NAMES}
    return dataclasses.replace(scenario, params=dataclasses.replace(p, **tighter, reserve=0.0))


def key(front, probability: bool):
    return [
        (f.points, round(f.length, 4), f.corrections, round(f.probability, 9) if probability else 0)
        for f in front
    ]


@pytest.mark.parametrize("probability", [False, True])
def test_a_reserve_plans_as_limits_lowered_by_its_metres(probability: bool) -> None:
    """Over random scenarios with turns, helices and unreliable points: the front planned with a
    reserve is the front of the same scenario whose limits are lowered by reserve x delta
    (proven both), equal to enumeration of every simple route, and it differs from the front
    without a reserve on some of them (the reserve is not ignored)."""
    changed = nonempty = 0
    for seed in range(40):
        base = tight_scenario(seed)
        rng = np.random.default_rng(1000 + seed)
        tightest = min(getattr(base.params, k) for k in LIMIT_NAMES) / base.params.delta
        reserve = float(rng.uniform(0.1, 0.5)) * tightest
        reserved = with_reserve(base, reserve)
        # Enumerated with its routes flown by prefix, once for both objective sets.
        result, want = assert_front_equals_prefix_enumeration(
            reserved, probability, ("tight_scenario with a reserve", seed)
        )
        lowered = bnb_front(
            with_tighter_limits(base, reserve), probability=probability, max_labels=10**6
        )
        assert lowered.optimal
        assert key(result.front, probability) == key(lowered.front, probability), seed
        plain = bnb_front(base, probability=probability, max_labels=10**6)
        changed += key(plain.front, probability) != key(result.front, probability)
        nonempty += bool(want)
    assert nonempty >= 12
    assert changed >= 4


def test_every_route_of_a_reserved_front_survives_a_flight_that_much_longer() -> None:
    """Fly each front route with any one leg ``reserve`` metres longer (so every stretch
    between resets that holds it is that much longer), held to the true limits: the exact
    probability of arriving is never below the one the plan promised, and on the all-success
    path every check keeps the reserve in metres."""
    checked = 0
    for seed in range(70):
        base = tight_scenario(seed)
        reserve = 0.2 * min(getattr(base.params, k) for k in LIMIT_NAMES) / base.params.delta
        reserved = with_reserve(base, reserve)
        result = bnb_front(reserved, probability=True, max_labels=10**6)
        for f in result.front:
            true = flown_route(base, f.points)
            for stop in true.stops[1:]:
                v_lim, h_lim = base.params.limits_m(stop.kind)
                assert stop.v_flown + reserve <= v_lim + 1e-6, seed
                assert stop.h_flown + reserve <= h_lim + 1e-6, seed
            lengths = [s.leg.length for s in true.stops[1:]]
            assert success_probability(reserved, f.points, lengths).probability == (
                pytest.approx(f.probability, abs=1e-12)
            )
            for i in range(len(lengths)):
                longer = [x + (reserve if k == i else 0.0) for k, x in enumerate(lengths)]
                p_flown = success_probability(base, f.points, longer).probability
                assert p_flown >= f.probability - 1e-12, (seed, i)
            checked += 1
    assert checked >= 20


def unreliable_scenario(seed: int):
    """Mostly unreliable points with a small failure residual: a failed correction there still
    cuts the error to the residual, so routes through them can be certain to arrive. Four
    correction points (65 routes to enumerate; the draw of 4 to 6 kept, so that the rest of the
    sample stays the same): as many fronts through an unreliable point (4) as with 4 to 6."""
    rng = np.random.default_rng(seed)
    share = float(rng.uniform(0.3, 0.6))
    params = Parameters(
        *(limit * share for limit in (25, 15, 20, 25, 30)),
        0.001,
        turn_radius=float(rng.choice([0.0, 200.0])),
        fail_residual=float(rng.uniform(0.5, 3.0)),
        max_climb_angle=15.0,
        max_descent_angle=15.0,
    )
    return random_scenario(
        min(int(rng.integers(4, 7)), 4), seed, params=params, box=(20_000, 5_000, 1_000),
        unreliable_fraction=0.7,
    )  # fmt: skip


def test_planning_with_every_unreliable_correction_failing_gives_the_certain_front() -> None:
    """A route arrives surely exactly when it survives every unreliable correction failing
    (a failure only leaves errors larger), so the front planned with p_success = 0 is the
    (length, corrections) front of the routes whose exact probability is 1, by enumeration."""
    from support.enumeration import pareto
    from support.prefix_flight import every_route_flown

    nonempty = through_unreliable = tried = 0
    for seed in range(46):
        scenario = tight_scenario(seed) if seed % 2 else unreliable_scenario(seed)
        # Both have at most 4 corrections: 65 routes to fly, not 1,957 with 6; each leg flown
        # once for the routes that share what comes before it (the same Route as flown_route).
        assert scenario.n <= 6
        tried += 1
        certain = []
        for pts, route in every_route_flown(scenario):
            legs = [s.leg for s in route.stops[1:]]
            if success_probability(scenario, pts, legs).probability == 1.0:
                certain.append((round(route.length, 6), route.corrections, 0.0))
        want = pareto(certain)
        failing = dataclasses.replace(
            scenario, params=dataclasses.replace(scenario.params, p_success=0.0)
        )
        result = bnb_front(failing, probability=True, max_labels=10**6)
        assert result.optimal
        got = [(round(f.length, 6), f.corrections, 0.0) for f in result.front]
        assert all(f.probability == 1.0 for f in result.front)
        assert [g[1] for g in got] == [w[1] for w in want], seed
        np.testing.assert_allclose([g[0] for g in got], [w[0] for w in want], atol=1e-6)
        nonempty += bool(want)
        through_unreliable += sum(
            any(scenario.unreliable[i] for i in f.points[1:-1]) for f in result.front
        )
    assert tried == 46 and nonempty >= 10
    assert through_unreliable >= 4  # certain although an unreliable correction may fail
