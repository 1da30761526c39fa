"""Seeds of the three-objective search: routes known before it starts, never a change of front."""

from __future__ import annotations

import numpy as np
from support.scenarios import uncertain_straight_scenario
from support.straight_walk import walked_straight_front

from gcs_planner.core.bnb import bnb_front
from gcs_planner.core.probability import success_probability
from gcs_planner.core.seeding import certain_front, reliable_seeds
from gcs_planner.scenario.generate import DATASET1, random_scenario


def test_reliable_seeds_are_simple_routes_certain_to_arrive() -> None:
    seeded = 0
    for seed in range(300):
        scenario = uncertain_straight_scenario(seed)
        for points in reliable_seeds(scenario):
            assert points[0] == scenario.start and points[-1] == scenario.end
            assert len(set(points)) == len(points)
            assert not scenario.unreliable[list(points)].any()
            assert success_probability(scenario, points).probability == 1.0
            seeded += 1
    assert seeded >= 50


def test_every_point_unreliable_gives_no_reliable_seed_but_a_direct_leg() -> None:
    scenario = random_scenario(
        6, 3, params=DATASET1, box=(20_000, 4_000, 500), unreliable_fraction=1
    )
    assert reliable_seeds(scenario) in ((), ((scenario.start, scenario.end),))


def test_fronts_seeded_with_certain_routes_equal_enumeration() -> None:
    """The planner's seeds (the certain front and the reliable points' front) as incumbents:
    the proven front stays the one of every simple route, on dense and corridor scenarios."""
    nonempty = used = 0
    for seed in range(400):
        scenario = uncertain_straight_scenario(seed)
        seeds = (*certain_front(scenario).seeds, *reliable_seeds(scenario))
        result = bnb_front(scenario, probability=True, max_labels=10**6, seeds=seeds)
        assert result.optimal
        got = [(round(f.length, 6), f.corrections, round(-f.probability, 12)) for f in result.front]
        want = walked_straight_front(scenario)
        assert [g[1:] for g in got] == [w[1:] for w in want], seed
        np.testing.assert_allclose([g[0] for g in got], [w[0] for w in want], atol=1e-6)
        nonempty += bool(want)
        used += bool(reliable_seeds(scenario))
    assert nonempty >= 100 and used >= 50
