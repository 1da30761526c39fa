"""The fanned depth-first walk (support/fan_walk.py), a reference the compiled searches are
held against, equals ``enumeration.dfs_front`` value for value: airplane legs with and without
climb limits, cs3d legs, a heading given at A, two and three objectives."""

from __future__ import annotations

import pytest
from support.enumeration import dfs_front
from support.fan_walk import fanned_dfs_front
from support.scenarios import climbing_scenario, turning_scenario

from gcs_planner.geometry.legs import scenario_leg_model


def _scenarios():
    for seed in range(4):
        yield turning_scenario(seed, [200.0, 1500.0][seed % 2])
        yield climbing_scenario(seed)
        yield turning_scenario(10 + seed, 800.0).with_vehicle(leg_model="cs3d")
    # a heading given at A: the first legs fanned too
    yield turning_scenario(20, 800.0).with_vehicle(heading_at_a=(0.0, 1.0, 0.0))


@pytest.mark.parametrize("probability", [True, False])
def test_the_fanned_walk_equals_the_walk_leg_by_leg(probability: bool) -> None:
    fanned = 0
    for x, scenario in enumerate(_scenarios()):
        got = fanned_dfs_front(scenario, probability)
        assert got == dfs_front(scenario, probability), x
        fanned += scenario_leg_model(scenario).carries_heading
    assert fanned >= 8
