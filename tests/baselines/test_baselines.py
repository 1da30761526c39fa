"""The independent comparators agree with each other and with the error model.

Brute force and the MILP share no search code (only the distance matrix and the error limits),
so their agreement on many random scenarios — dense ones with several-point fronts, sparse ones,
infeasible ones — is the evidence that both are exact. NSGA-II is a heuristic: it may miss front
points but must never beat the true front or return an infeasible route.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcs_planner.baselines.brute import brute_force_front
from gcs_planner.baselines.milp import length_cap, milp_front, milp_shortest
from gcs_planner.baselines.nsga2 import nsga2_front
from gcs_planner.core.route import evaluate_route
from gcs_planner.scenario.generate import DATASET1, DATASET2, random_scenario
from gcs_planner.scenario.model import Kind, Parameters, Scenario

TOL_M = 1e-6

DENSE = (40_000.0, 20_000.0, 2_000.0)
SPARSE = (50_000.0, 20_000.0, 2_000.0)  # most chains fail; few routes exist
CORRIDOR = (45_000.0, 4_000.0, 400.0)  # long and narrow: fronts with several points


def make_scenario(points: list[tuple[str, tuple[float, float, float]]], params: Parameters):
    """A scenario from (kind letter, xyz) rows, A first and B last."""
    codes = {"A": Kind.A, "B": Kind.B, "V": Kind.V, "H": Kind.H}
    return Scenario(
        ids=tuple(str(i) for i in range(len(points))),
        xyz=np.array([xyz for _, xyz in points], dtype=float),
        kind=np.array([codes[k] for k, _ in points], dtype=np.uint8),
        unreliable=np.zeros(len(points), dtype=bool),
        params=params,
    )


def assert_same_front(brute, milp) -> None:
    assert [k for _, k, _ in brute] == [k for _, k, _ in milp]
    for (lb, _, _), (lm, _, _) in zip(brute, milp, strict=True):
        assert abs(lb - lm) <= TOL_M


def assert_valid_front(scenario: Scenario, front) -> None:
    """Feasible simple routes, lengths and counts as evaluate_route says, strictly trading
    corrections for length."""
    for length, k, route in front:
        evaluated = evaluate_route(scenario, route)
        assert evaluated.feasible and evaluated.simple
        assert evaluated.length == length
        assert evaluated.corrections == k
    assert [k for _, k, _ in front] == sorted({k for _, k, _ in front})
    lengths = [length for length, _, _ in front]
    assert all(a > b for a, b in zip(lengths[:-1], lengths[1:], strict=True))


def shortest_within(front, k: int) -> float:
    """Shortest length with at most k corrections, read off a front (inf if none)."""
    return min((length for length, c, _ in front if c <= k), default=math.inf)


# --- brute force against the MILP ---------------------------------------------------------


@pytest.mark.parametrize(
    ("box", "params", "counts", "seeds"),
    [
        (DENSE, DATASET1, range(4, 9), range(6)),
        (SPARSE, DATASET1, range(4, 9), range(4)),
        ((30_000.0, 15_000.0, 1_500.0), DATASET2, range(4, 9), range(4)),
        (CORRIDOR, DATASET1, (9, 10), range(12)),
    ],
    ids=["dense-d1", "sparse-d1", "dense-d2", "corridor-d1"],
)
def test_brute_force_front_equals_milp_front(box, params, counts, seeds) -> None:
    shapes = {"infeasible": 0, "single": 0, "several": 0}
    for n in counts:
        for seed in seeds:
            scenario = random_scenario(n, seed, params=params, box=box)
            brute = brute_force_front(scenario)
            assert_valid_front(scenario, brute)
            milp = milp_front(scenario)
            assert_valid_front(scenario, milp)
            assert_same_front(brute, milp)
            shapes[["infeasible", "single", "several"][min(len(brute), 2)]] += 1
    # The sample must exercise what it claims to: the corridor gives fronts of several points,
    # the others infeasible scenarios besides feasible ones.
    if box == CORRIDOR:
        assert shapes["several"] > 0
    else:
        assert shapes["infeasible"] > 0 and shapes["single"] + shapes["several"] > 0


@settings(max_examples=20, deadline=None)
@given(
    n=st.integers(4, 8),
    seed=st.integers(0, 10_000),
    length=st.floats(25_000.0, 60_000.0),
    width=st.floats(2_000.0, 40_000.0),
)
def test_brute_and_milp_agree_on_random_boxes(n, seed, length, width) -> None:
    scenario = random_scenario(n, seed, params=DATASET1, box=(length, width, width / 10))
    assert_same_front(brute_force_front(scenario), milp_front(scenario))


def test_milp_shortest_with_each_cap_matches_brute_force() -> None:
    for seed in range(8):
        scenario = random_scenario(10, seed, params=DATASET1, box=CORRIDOR)
        brute = brute_force_front(scenario)
        for k in range(0, 5):
            res = milp_shortest(scenario, k)
            expected = shortest_within(brute, k)
            if math.isinf(expected):
                assert res.status == "infeasible" and res.route is None and res.optimal
            else:
                assert res.status == "optimal" and res.optimal
                assert res.corrections is not None and res.corrections <= k
                assert abs(res.length - expected) <= TOL_M
                assert evaluate_route(scenario, res.route).feasible


def test_milp_upper_bound_prunes_without_losing_the_optimum() -> None:
    checked = 0
    for seed in range(8):
        scenario = random_scenario(8, seed, params=DATASET1, box=DENSE)
        brute = brute_force_front(scenario)
        if not brute:
            continue
        checked += 1
        best, k = brute[-1][0], brute[-1][1]
        for bound in (best, best + 500.0):
            res = milp_shortest(scenario, k, upper_bound=bound)
            assert res.optimal and abs(res.length - best) <= TOL_M
        # A bound below the optimum leaves no route: the bound is trusted, not checked.
        assert milp_shortest(scenario, k, upper_bound=best - 1.0).status == "infeasible"
    assert checked > 0


@settings(max_examples=30, deadline=None)
@given(n=st.integers(4, 8), seed=st.integers(0, 10_000), k=st.integers(0, 8))
def test_length_cap_bounds_every_feasible_route(n, seed, k) -> None:
    scenario = random_scenario(n, seed, params=DATASET2, box=DENSE)
    for length, c, _ in brute_force_front(scenario):
        if c <= k:
            assert length <= length_cap(scenario, k)


# --- brute force on its own -----------------------------------------------------------------


def test_brute_force_caps_corrections_to_a_prefix_of_the_front() -> None:
    for seed in range(10):
        scenario = random_scenario(10, seed, params=DATASET1, box=CORRIDOR)
        full = brute_force_front(scenario)
        for cap in range(0, 4):
            assert brute_force_front(scenario, max_corrections=cap) == [
                p for p in full if p[1] <= cap
            ]


def test_direct_flight_is_the_whole_front_when_b_is_within_theta() -> None:
    # |AB| = 25 km ≤ θ/δ = 30 km: the straight line is the shortest possible route, so no
    # correction can buy length and the front is this one point.
    scenario = make_scenario(
        [
            ("A", (0.0, 0.0, 0.0)),
            ("V", (10_000.0, 1_000.0, 0.0)),
            ("H", (15_000.0, -500.0, 0.0)),
            ("B", (25_000.0, 0.0, 0.0)),
        ],
        DATASET1,
    )
    expected = [(25_000.0, 0, (0, 3))]
    assert brute_force_front(scenario) == expected
    assert_same_front(expected, milp_front(scenario))


def test_a_feasible_walk_through_a_repeated_point_is_not_a_route() -> None:
    # V at 14 km from A, H 10 km off it, B 19 km beyond V (DATASET1, limits in metres:
    # V (25k, 15k), H (20k, 25k), B (30k, 30k)). Only A, V, H, V, B keeps both errors in
    # bounds; every simple route passes a limit (worked by hand: A-V-B arrives with h = 33 km,
    # A-H-V-B reaches V with v = 27.2 km, A-V-H-B and A-H-B reach B with v > 30 km).
    scenario = make_scenario(
        [
            ("A", (0.0, 0.0, 0.0)),
            ("V", (14_000.0, 0.0, 0.0)),
            ("H", (14_000.0, 10_000.0, 0.0)),
            ("B", (33_000.0, 0.0, 0.0)),
        ],
        DATASET1,
    )
    walk = evaluate_route(scenario, (0, 1, 2, 1, 3))
    assert walk.feasible and not walk.simple
    assert brute_force_front(scenario) == []
    assert milp_front(scenario) == []
    assert milp_shortest(scenario, 5).status == "infeasible"


def test_front_points_beat_each_other_in_one_objective_only() -> None:
    several = 0
    for seed in range(12):
        scenario = random_scenario(10, seed, params=DATASET1, box=CORRIDOR)
        front = brute_force_front(scenario)
        assert_valid_front(scenario, front)
        several += len(front) > 1
    assert several > 0


# --- NSGA-II --------------------------------------------------------------------------------


@pytest.mark.parametrize("forward_only", [True, False])
def test_nsga2_returns_feasible_routes_that_never_beat_the_exact_front(forward_only) -> None:
    found = 0
    for seed in range(6):
        scenario = random_scenario(9, seed, params=DATASET1, box=CORRIDOR)
        exact = brute_force_front(scenario)
        result = nsga2_front(scenario, seed=seed, pop_size=20, n_gen=15, forward_only=forward_only)
        assert 0 < result.evaluations <= 20 * 15  # the budget is honoured
        for length, k, route in result.front:
            evaluated = evaluate_route(scenario, route)
            assert evaluated.feasible and evaluated.simple
            assert abs(evaluated.length - length) <= TOL_M and evaluated.corrections == k
            assert length >= shortest_within(exact, k) - TOL_M
        if not exact:
            assert result.front == []
        found += bool(result.front)
    assert found > 0


def test_nsga2_is_repeatable_with_a_seed() -> None:
    scenario = random_scenario(9, 4, params=DATASET1, box=DENSE)
    first = nsga2_front(scenario, seed=7, pop_size=16, n_gen=8)
    again = nsga2_front(scenario, seed=7, pop_size=16, n_gen=8)
    assert first.front == again.front and first.evaluations == again.evaluations


def test_nsga2_without_correction_points() -> None:
    reachable = make_scenario([("A", (0.0, 0.0, 0.0)), ("B", (20_000.0, 0.0, 0.0))], DATASET1)
    assert nsga2_front(reachable).front == [(20_000.0, 0, (0, 1))]
    too_far = make_scenario([("A", (0.0, 0.0, 0.0)), ("B", (40_000.0, 0.0, 0.0))], DATASET1)
    assert nsga2_front(too_far).front == []
