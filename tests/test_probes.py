"""The probes of the branch and bound with turns (``bnb._Prober``): a partial route over simple
routes is dropped when every completion of it in the relaxation that proved the floor is
dominated by a route already found, and so is every partial route that a probe which proved
this expanded (its nogoods). The fronts must stay those of enumeration while the probes prune.

The scenarios where probes prune have nine to fourteen points, too many for enumerating every
permutation; ``dfs_front`` enumerates every simple route depth first instead, dropping a prefix
only when no error branch survives it (every extension of it is then infeasible too), and is
itself checked against the plain enumeration on small scenarios."""

from __future__ import annotations

import collections
import functools

import numpy as np
import pytest
from test_airplane_legs import climbing_scenario
from test_bnb import enumerate_front, turning_scenario

from gcs_planner.core import bnb
from gcs_planner.core.bnb import Options, probes
from gcs_planner.core.probability import propagate
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Kind, Parameters


def dfs_front(scenario, probability: bool) -> list[tuple[float, int, float]]:
    """The Pareto front of (length, corrections, -probability) over every simple route, each
    leg flown from the heading the previous one ended with (sorted like ``enumerate_front``)."""
    model = scenario_leg_model(scenario)
    xyz, params, n = scenario.xyz, scenario.params, scenario.n
    kind = [Kind(int(c)) for c in scenario.kind]
    unreliable = scenario.unreliable if probability else np.zeros(n, dtype=bool)
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a)
    values = []

    def extend(path, heading, length, states) -> None:
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
    front: list[tuple[float, int, float]] = []
    for v in sorted(set(values)):  # by length: only an earlier value can dominate a later one
        if not any(all(x <= y for x, y in zip(kept, v)) for kept in front):
            front.append(v)
    if not probability:
        front = [(length, k, 0.0) for length, k, _ in front]
    return sorted(front, key=lambda t: (t[1], t[0], t[2]))


def probed_scenario(seed: int, legs: str):
    """Nine to thirteen correction points, half of them unreliable, limits of 10 to 18 km and
    radii of 500 to 1,500 m in a 24 km corridor: routes of several corrections whose turns
    matter, so that the search over simple routes probes many partial routes."""
    rng = np.random.default_rng(70_000 + seed)
    climb = legs == "airplane, climb limits"
    params = Parameters(
        *rng.uniform(10_000, 18_000, 5) * 0.001,
        0.001,
        turn_radius=float(rng.choice([500.0, 1000.0, 1500.0])),
        p_success=float(rng.choice([0.5, 0.8])),
        fail_residual=float(rng.uniform(2, 15)),
        max_climb_angle=float(rng.choice([8.0, 15.0])) if climb else 90.0,
        max_descent_angle=float(rng.choice([8.0, 15.0])) if climb else 90.0,
    )
    scenario = random_scenario(
        int(rng.integers(9, 12)),
        seed,
        params=params,
        box=(24_000, 8_000, 3_000 if climb else 1_000),
        unreliable_fraction=0.5,
    )
    return scenario.with_vehicle(leg_model="cs3d") if legs == "cs3d" else scenario


@functools.cache
def probed_front(seed: int, legs: str, probability: bool) -> list[tuple[float, int, float]]:
    """``dfs_front`` of ``probed_scenario(seed, legs)``, enumerated once per test session (the
    tests of the probes and of the compiled searches ask for the same scenarios)."""
    return dfs_front(probed_scenario(seed, legs), probability)


def front_of(result, probability: bool) -> list[tuple[float, int, float]]:
    return [
        (round(f.length, 6), f.corrections, round(-f.probability, 12) if probability else 0.0)
        for f in result.front
    ]


def assert_same_front(got, want, seed) -> None:
    assert [g[1:] for g in got] == [w[1:] for w in want], seed
    np.testing.assert_allclose([g[0] for g in got], [w[0] for w in want], atol=1e-6)


@pytest.mark.parametrize("probability", [True, False], ids=["3 objectives", "2 objectives"])
def test_the_depth_first_enumeration_equals_the_plain_one(probability: bool) -> None:
    nonempty = 0
    for seed in range(12):
        scenario = climbing_scenario(seed) if seed % 2 else turning_scenario(seed, 1500.0)
        want = enumerate_front(scenario, probability)
        assert_same_front(dfs_front(scenario, probability), want, seed)
        nonempty += bool(want)
    assert nonempty >= 6


# Small searches probe from their first label.
FROM_FIRST_LABEL = Options(probe_from=0)


@pytest.fixture
def probe_outcomes(monkeypatch) -> collections.Counter:
    """Counts what the probes answered: covered (and of those, from nogoods alone) or open."""
    outcomes: collections.Counter[str] = collections.Counter()
    probe = probes._Prober.__call__

    def counted(self, entry, inc, budget):
        covered, spent = probe(self, entry, inc, budget)
        outcomes["covered" if covered else "open"] += 1
        outcomes["by nogoods"] += covered and spent == 0
        return covered, spent

    monkeypatch.setattr(probes._Prober, "__call__", counted)
    return outcomes


def test_fronts_with_probes_equal_enumeration(probe_outcomes) -> None:
    nonempty = 0
    for legs in ("airplane", "airplane, climb limits", "cs3d"):
        for seed in range(12):
            scenario = probed_scenario(seed, legs)
            result = bnb.bnb_front(
                scenario, probability=True, max_labels=10**6, options=FROM_FIRST_LABEL
            )
            assert result.optimal
            want = probed_front(seed, legs, True)
            assert_same_front(front_of(result, True), want, (legs, seed))
            nonempty += bool(want)
    assert nonempty >= 15
    # The probes were asked, pruned partial routes, and answered some from their nogoods.
    assert probe_outcomes["covered"] >= 40 and probe_outcomes["by nogoods"] >= 10, probe_outcomes
    assert probe_outcomes["open"] >= 100, probe_outcomes


def test_two_objective_fronts_with_probes_equal_enumeration(probe_outcomes) -> None:
    for legs in ("airplane", "cs3d"):
        for seed in range(6):
            scenario = probed_scenario(seed, legs)
            result = bnb.bnb_front(
                scenario, probability=False, max_labels=10**6, options=FROM_FIRST_LABEL
            )
            assert result.optimal
            want = probed_front(seed, legs, False)
            assert_same_front(front_of(result, False), want, (legs, seed))
    assert probe_outcomes["open"] >= 20, probe_outcomes
