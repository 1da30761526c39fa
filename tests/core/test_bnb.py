"""Branch and bound with turns and uncertain corrections against exhaustive enumeration."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from support.prefix_fronts import assert_front_equals_prefix_enumeration
from support.scenarios import mixed_scenario, turning_scenario, uncertain_straight_scenario
from support.straight_walk import walked_straight_front

from gcs_planner.core.bnb import Options, bnb_front, flown_route
from gcs_planner.core.probability import success_probability
from gcs_planner.core.search import straight_front


@pytest.mark.parametrize("probability", [False, True])
def test_front_with_turns_equals_enumeration(probability: bool) -> None:
    nonempty = uncertain = 0
    for seed in range(60):
        # at most 4 points: 65 routes to fly, not 326; the same draws
        radius = [200.0, 1500.0, 4000.0][seed % 3]
        scenario = turning_scenario(seed, radius, max_points=4)
        # Enumerated with its routes flown by prefix, once for both objective sets.
        _, want = assert_front_equals_prefix_enumeration(
            scenario, probability, ("turning_scenario", seed, radius, 4)
        )
        nonempty += bool(want)
        uncertain += any(w[2] > -1 for w in want)
    assert nonempty >= 20
    assert uncertain >= 3 or not probability, "failures must matter in some scenarios"


def test_turns_never_shorten_and_straight_front_is_a_lower_bound() -> None:
    for seed in range(40):
        scenario = turning_scenario(seed, radius=1000.0)
        straight = straight_front(scenario.with_params(turn_radius=0.0))
        turned = bnb_front(scenario, probability=False, max_labels=10**6)
        for f in turned.front:
            best_straight = min(
                (s.length for s in straight.front if s.corrections <= f.corrections),
                default=np.inf,
            )
            assert f.length >= best_straight - 1e-9


def test_branch_and_bound_without_turns_agrees_with_the_layered_search() -> None:
    for seed in range(80):
        scenario = mixed_scenario(seed)
        layered = straight_front(scenario)
        bnb = bnb_front(scenario, probability=False, max_labels=10**6)
        assert [f.corrections for f in bnb.front] == [f.corrections for f in layered.front]
        np.testing.assert_allclose(
            [f.length for f in bnb.front], [f.length for f in layered.front], atol=1e-6
        )


def test_budget_reports_gaps_instead_of_claiming_optimality(dataset_paths) -> None:
    from gcs_planner.scenario.generate import DATASET1
    from gcs_planner.scenario.readers import load_scenario

    scenario = load_scenario(dataset_paths[1], DATASET1.to_dict())
    full = bnb_front(scenario, probability=True, max_labels=10**6)
    assert full.optimal
    result = bnb_front(scenario, probability=True, max_labels=max(1, full.labels // 5))
    assert not result.optimal and result.open_labels > 0
    for f, lb in zip(result.front, result.lower_bounds):
        assert lb <= f.length + 1e-9
        # A proven lower bound: no route of the exact front that is as good on corrections and
        # probability is shorter than it.
        exact = min(
            g.length
            for g in full.front
            if g.corrections <= f.corrections and g.probability >= f.probability - 1e-12
        )
        assert lb <= exact + 1e-6
        again = flown_route(scenario, f.points)
        assert again.feasible and again.length == pytest.approx(f.length, abs=1e-6)


def test_straight_three_objective_front_equals_enumeration() -> None:
    """With straight legs the search compares partial routes by dominance (length,
    corrections, error-state distribution) over walks, made exact by decremental relaxation:
    it must still give exactly the front of simple routes."""
    nonempty = uncertain = relaxed = 0
    for seed in range(800):
        scenario = uncertain_straight_scenario(seed)
        result = bnb_front(scenario, probability=True, max_labels=10**6)
        assert result.optimal
        got = [(round(f.length, 6), f.corrections, round(-f.probability, 12)) for f in result.front]
        want = walked_straight_front(scenario)
        assert [g[1:] for g in got] == [w[1:] for w in want], seed
        np.testing.assert_allclose([g[0] for g in got], [w[0] for w in want], atol=1e-6)
        for f in result.front:
            assert len(set(f.points)) == len(f.points)
        nonempty += bool(want)
        uncertain += any(-1 < w[2] < 0 for w in want)
        relaxed += result.rounds > 1
    assert nonempty >= 200
    assert uncertain >= 25, "failures must matter in some scenarios"
    assert relaxed >= 5, "some scenarios must need the decremental relaxation"


def test_dominance_on_real_data_agrees_with_the_search_over_simple_routes(dataset_paths) -> None:
    from gcs_planner.scenario.generate import DATASET1
    from gcs_planner.scenario.readers import load_scenario

    scenario = load_scenario(dataset_paths[1], DATASET1.to_dict() | {"turn_radius": 0.0})
    fast = bnb_front(scenario, probability=True)
    plain = bnb_front(scenario, probability=True, dominance=False, max_labels=10**6)
    assert fast.optimal and plain.optimal
    assert [(f.corrections, f.probability) for f in fast.front] == [
        (f.corrections, f.probability) for f in plain.front
    ]
    np.testing.assert_allclose(
        [f.length for f in fast.front], [f.length for f in plain.front], atol=1e-6
    )


@pytest.mark.parametrize("dataset", [1, 2])
@pytest.mark.parametrize("probability", [False, True])
def test_contest_fronts_with_turns_re_evaluate_to_the_same_flown_length(
    dataset_paths, dataset: int, probability: bool
) -> None:
    """The search adds up its own vectorised CS legs; the trajectory module flies each reported
    route again from scratch. Both must agree, and the lower bounds must be bounds."""
    from gcs_planner.scenario.generate import DATASET1, DATASET2
    from gcs_planner.scenario.readers import load_scenario

    params = (DATASET1 if dataset == 1 else DATASET2).to_dict() | {"turn_radius": 200.0}
    scenario = load_scenario(dataset_paths[dataset], params)
    result = bnb_front(scenario, probability=probability)
    assert result.front
    if not probability:
        assert result.optimal  # both workbooks' two-objective fronts are proven
    for f, lb in zip(result.front, result.lower_bounds):
        again = flown_route(scenario, f.points)
        assert again.feasible
        assert abs(again.length - f.length) <= 1e-6
        assert lb <= f.length + 1e-9
        if probability:
            legs = [s.leg for s in again.stops[1:]]
            p = success_probability(scenario, f.points, legs).probability
            assert abs(p - f.probability) <= 1e-12


@pytest.mark.parametrize("probability", [False, True])
def test_front_is_exact_with_a_cost_to_go_cut_short(monkeypatch, probability: bool) -> None:
    """A time limit cuts the cost-to-go's layers short (and the pair and failure bounds'): the
    weaker bounds must leave the search exact. Here every table stops after 0 or 1 layers (B's
    own arcs)."""
    from gcs_planner.core import cost_to_go, failure_bounds, pair_bounds
    from gcs_planner.core.bnb import context

    layers = 0

    def cut_short(*args, **kwargs):
        asked = itertools.count(0)
        return cost_to_go.cost_to_go(*args, **{**kwargs, "stop": lambda: next(asked) >= layers})

    monkeypatch.setattr(context, "cost_to_go", cut_short)
    monkeypatch.setattr(pair_bounds, "cost_to_go", cut_short)
    monkeypatch.setattr(failure_bounds, "cost_to_go", cut_short)
    at_once = Options(failure_bounds_per_arc=0.0)  # the failure bounds made (and cut) at once
    cut = failures_cut = 0
    for seed in range(20):
        layers = seed % 2
        radius = [200.0, 1500.0, 0.0][seed % 3]
        scenario = turning_scenario(seed, radius, max_points=4)
        # Enumerated by prefix, once per scenario for this test and the first one above.
        result, _ = assert_front_equals_prefix_enumeration(
            scenario, probability, ("turning_scenario", seed, radius, 4), at_once
        )
        cut += any(c.startswith("the cost-to-go:") for c in result.cut)
        failures_cut += any(c.startswith("the bounds per probability") for c in result.cut)
    assert cut >= 10
    assert failures_cut >= 5 or not probability
