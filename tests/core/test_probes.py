"""The probes of the branch and bound with turns (``bnb._Prober``): a partial route over simple
routes is dropped when every completion of it in the relaxation that proved the floor is
dominated by a route already found, and so is every partial route that a probe which proved
this expanded (its nogoods). The fronts must stay those of enumeration while the probes prune.

The scenarios where probes prune have nine to fourteen points, too many for enumerating every
permutation; ``dfs_front`` (support/enumeration.py) enumerates every simple route depth first
instead, dropping a prefix only when no error branch survives it (every extension of it is then
infeasible too), and is itself checked against the plain enumeration on small scenarios."""

from __future__ import annotations

import collections

import pytest
from support.enumeration import (
    assert_same_front,
    dfs_front,
    front_of,
    probed_front,
)
from support.prefix_fronts import prefix_front
from support.scenarios import climbing_scenario, probed_scenario, turning_scenario

from gcs_planner.core import bnb
from gcs_planner.core.bnb import Options, probes


@pytest.mark.parametrize("probability", [True, False], ids=["3 objectives", "2 objectives"])
def test_the_depth_first_enumeration_equals_the_plain_one(probability: bool) -> None:
    nonempty = 0
    for seed in range(12):
        if seed % 2:
            scenario, question = climbing_scenario(seed), ("climbing_scenario", seed, 5)
        else:
            scenario = turning_scenario(seed, 1500.0)
            question = ("turning_scenario", seed, 1500.0, 5)
        # Every simple route flown by prefix (the same Route as flown_route, held so in
        # test_prefix_flight.py), once for both objective sets.
        want = prefix_front(scenario, probability, question)
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
