"""Success probability under uncertain corrections: exact chain, brute force, Monte Carlo."""

from __future__ import annotations

import functools
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from support.paths import DATA

from gcs_planner.core.probability import (
    brute_force_success,
    monte_carlo_success,
    propagate,
    success_probability,
)
from gcs_planner.core.route import Leg, evaluate_route, straight_legs
from gcs_planner.scenario.generate import DATASET1, random_scenario
from gcs_planner.scenario.model import Kind, Parameters, Scenario
from gcs_planner.scenario.readers import load_scenario

# A small box against DATASET1's reach (15-30 km limits) so that the limits bind and a failed
# correction (residual 5 km) often makes the difference.
BOX = (30_000.0, 15_000.0, 3_000.0)


def _walk(scenario: Scenario, rng: np.random.Generator, corrections: int) -> list[int]:
    """A random chain that stays feasible while all corrections succeed, as far as it can."""
    params = scenario.params
    points = [scenario.start]
    dv = dh = 0.0
    while len(points) - 1 < corrections:
        here = scenario.xyz[points[-1]]
        options = []
        for j in range(scenario.n):
            if j in points or scenario.kind[j] in (Kind.A, Kind.B):
                continue
            d = float(np.linalg.norm(scenario.xyz[j] - here))
            v_lim, h_lim = params.limits_m(Kind(int(scenario.kind[j])))
            if dv + d <= v_lim and dh + d <= h_lim:
                options.append((j, d))
        if not options:
            break
        j, d = options[int(rng.integers(len(options)))]
        points.append(j)
        dv, dh = dv + d, dh + d
        if scenario.kind[j] == Kind.V:
            dv = 0.0
        else:
            dh = 0.0
    return [*points, scenario.end]


def _shuffled(scenario: Scenario, rng: np.random.Generator, corrections: int) -> list[int]:
    """A random chain in random order: mostly infeasible even when every correction succeeds."""
    inner = rng.choice(np.arange(1, scenario.n - 1), size=corrections, replace=False)
    return [scenario.start, *(int(i) for i in inner), scenario.end]


@functools.lru_cache(maxsize=1)
def _sample() -> tuple[tuple[Scenario, tuple[int, ...]], ...]:
    """Seeded random routes of 3 to 12 points over small random scenarios."""
    rng = np.random.default_rng(20190921)
    routes = []
    for seed in range(80):
        p_success = (0.8, 0.5, 0.2, 0.95)[seed % 4]
        scenario = random_scenario(12, seed, box=BOX, unreliable_fraction=0.5).with_params(
            p_success=p_success
        )
        for _ in range(3):
            corrections = int(rng.integers(1, 11))
            make = _walk if rng.random() < 0.8 else _shuffled
            routes.append((scenario, tuple(make(scenario, rng, corrections))))
    return tuple(routes)


def _unreliable_on(scenario: Scenario, points) -> int:
    return int(sum(bool(scenario.unreliable[j]) for j in points[1:-1]))


def test_exact_equals_brute_force_on_random_routes() -> None:
    zero_infeasible = strictly_between = certain = 0
    for scenario, points in _sample():
        exact = success_probability(scenario, points)
        reference = brute_force_success(scenario, points)
        assert exact.probability == pytest.approx(reference, abs=1e-12), (scenario.name, points)
        assert 0.0 <= exact.probability <= 1.0
        feasible = evaluate_route(scenario, points).feasible
        if not feasible:
            # A failure never lowers an error, so an all-success violation is a sure violation.
            assert exact.probability == 0.0
            zero_infeasible += 1
        elif exact.probability == 1.0:
            certain += 1
        elif 0.0 < exact.probability < 1.0:
            strictly_between += 1
    # The sample must exercise every case, or the equality above proves little.
    assert zero_infeasible >= 20
    assert strictly_between >= 20
    assert certain >= 5


def test_per_stop_is_the_arrival_probability_and_non_increasing() -> None:
    for scenario, points in _sample():
        result = success_probability(scenario, points)
        assert len(result.per_stop) == len(points)
        assert result.per_stop[0] == 1.0
        assert result.per_stop[-1] == result.probability
        # Mass is only ever dropped; 1e-12 absorbs the rounding of p*m + (1-p)*m.
        for before, after in zip(result.per_stop, result.per_stop[1:], strict=False):
            assert after <= before + 1e-12
        # Arriving within limits at a stop is succeeding on the prefix that ends there and then
        # flies a zero-length leg to a B whose theta never binds: brute force that.
        legs = straight_legs(scenario, points)
        open_end = scenario.with_params(theta=1e12)
        for stop in range(1, len(points) - 1):
            prefix = [*points[: stop + 1], scenario.end]
            expected = brute_force_success(open_end, prefix, [*legs[:stop], 0.0])
            assert result.per_stop[stop] == pytest.approx(expected, abs=1e-12)


def test_no_unreliable_points_gives_the_deterministic_answer() -> None:
    seen = set()
    for scenario, points in _sample():
        reliable = replace(scenario, unreliable=np.zeros(scenario.n, dtype=bool))
        feasible = evaluate_route(reliable, points).feasible
        result = success_probability(reliable, points)
        assert result.probability == (1.0 if feasible else 0.0)
        assert result.states == 1
        seen.add(feasible)
    assert seen == {True, False}


def test_p_success_one_gives_the_deterministic_answer() -> None:
    for scenario, points in _sample():
        sure = scenario.with_params(p_success=1.0)
        route = evaluate_route(sure, points)
        result = success_probability(sure, points)
        assert result.probability == (1.0 if route.feasible else 0.0)
        # Per stop: 1 up to the first violation, 0 from there on.
        violation = route.first_violation()
        cut = len(points) if violation is None else route.stops.index(violation)
        assert result.per_stop == tuple([1.0] * cut + [0.0] * (len(points) - cut))


def test_p_success_zero_matches_brute_force() -> None:
    for scenario, points in _sample()[:60]:
        never = scenario.with_params(p_success=0.0)
        assert success_probability(never, points).probability == pytest.approx(
            brute_force_success(never, points), abs=1e-12
        )


def _state_bound(scenario: Scenario, points) -> int:
    """(k_v + 1) * (k_h + 1), k counting unreliable points of a kind since the last reliable
    one of that kind, maximised along the route (proof in gcs_planner/core/probability.py)."""
    k_v = k_h = 0
    bound = 1
    for j in points[1:-1]:
        unreliable = bool(scenario.unreliable[j])
        if scenario.kind[j] == Kind.V:
            k_v = k_v + 1 if unreliable else 0
        else:
            k_h = k_h + 1 if unreliable else 0
        bound = max(bound, (k_v + 1) * (k_h + 1))
    return bound


def test_merging_keeps_the_state_count_within_its_bound() -> None:
    merged_something = False
    for scenario, points in _sample():
        result = success_probability(scenario, points)
        assert result.states <= _state_bound(scenario, points)
        # Without merging the chain would hold 2^k paths.
        k = _unreliable_on(scenario, points)
        merged_something |= k >= 3 and result.states < 2**k
    assert merged_something


def _line_scenario(kinds: list[Kind], unreliable: list[bool], params: Parameters) -> Scenario:
    n = len(kinds)
    return Scenario(
        ids=tuple(str(i) for i in range(n)),
        xyz=np.zeros((n, 3)),
        kind=np.array(kinds, dtype=np.uint8),
        unreliable=np.array(unreliable, dtype=bool),
        params=params,
    )


def test_hand_worked_route() -> None:
    # A -10 km- V1? -3 km- V2? -2 km- H -10 km- B, limits 100 everywhere except theta = 16.
    # After V2 the vertical error (m) is 0 (V2 succeeds), 3000 (V1 ok, V2 fails: min(3000, 5000))
    # or 5000 (both fail); at B it is 12000, 15000 or 17000 against 16000, so the route fails
    # only when both corrections fail: P = 1 - (1 - p)^2.
    params = Parameters(100, 100, 100, 100, 16, 0.001, p_success=0.7, fail_residual=5)
    scenario = _line_scenario(
        [Kind.A, Kind.V, Kind.V, Kind.H, Kind.B], [False, True, True, False, False], params
    )
    legs = [10_000.0, 3_000.0, 2_000.0, 10_000.0]
    result = success_probability(scenario, range(5), legs)
    assert result.probability == pytest.approx(1 - 0.3**2, abs=1e-15)
    assert result.per_stop[:4] == (1.0, 1.0, 1.0, 1.0)
    assert result.states == 3  # the bound (2 + 1) * (0 + 1) is reached


def test_a_limit_reached_exactly_is_met() -> None:
    # A -10 km- H? -5 km- V -L- B with dataset-1 limits (theta 30 -> 30000 m). A failed H leaves
    # h = min(10000, 5000) = 5000, so at B h = 5000 + 5000 + L: exactly 30000 for L = 20000,
    # which is within the limit; one ulp more fails exactly when the H correction fails.
    scenario = _line_scenario(
        [Kind.A, Kind.H, Kind.V, Kind.B], [False, True, False, False], DATASET1
    )
    at_limit = [10_000.0, 5_000.0, 20_000.0]
    beyond = [10_000.0, 5_000.0, float(np.nextafter(20_000.0, np.inf))]
    assert success_probability(scenario, range(4), at_limit).probability == 1.0
    assert brute_force_success(scenario, range(4), at_limit) == 1.0
    assert monte_carlo_success(scenario, range(4), at_limit, runs=1000).rate == 1.0
    p = DATASET1.p_success
    assert success_probability(scenario, range(4), beyond).probability == pytest.approx(p)
    assert brute_force_success(scenario, range(4), beyond) == pytest.approx(p)


def test_propagate_single_step() -> None:
    params = Parameters(25, 15, 20, 25, 30, 0.001, p_success=0.8, fail_residual=5)
    start = {(0.0, 0.0): 0.5, (4000.0, 1000.0): 0.5}
    states, arrived = propagate(start, 12_000.0, Kind.V, True, params)
    # (16000, 13000) is within (25000, 15000); (12000, 12000) too. Failure clips v to 5000.
    assert arrived == pytest.approx(1.0)
    assert states == pytest.approx(
        {
            (0.0, 12_000.0): 0.4,
            (5000.0, 12_000.0): 0.1,
            (0.0, 13_000.0): 0.4,
            (5000.0, 13_000.0): 0.1,
        }
    )
    # Horizontal limit 15000 at V drops the state that arrives at 16000 horizontally.
    states, arrived = propagate(start, 15_000.0, Kind.V, False, params)
    assert arrived == 0.5
    assert states == {(0.0, 15_000.0): 0.5}
    # B checks, never corrects.
    states, arrived = propagate({(1.0, 2.0): 1.0}, 3.0, Kind.B, True, params)
    assert states == {(4.0, 5.0): 1.0} and arrived == 1.0


@settings(max_examples=150, deadline=None)
@given(
    steps=st.lists(
        st.tuples(
            st.sampled_from([Kind.V, Kind.H]),
            st.booleans(),
            st.one_of(st.floats(0.0, 16_000.0), st.sampled_from([5_000.0, 10_000.0, 15_000.0])),
        ),
        min_size=1,
        max_size=10,
    ),
    last_leg=st.floats(0.0, 30_000.0),
    p_success=st.sampled_from([0.0, 0.3, 0.8, 1.0]),
)
def test_exact_equals_brute_force_on_arbitrary_legs(steps, last_leg, p_success) -> None:
    # Leg lengths hit the limits and the residual exactly, where a float mismatch would show.
    params = replace(DATASET1, p_success=p_success)
    kinds = [Kind.A, *(k for k, _, _ in steps), Kind.B]
    flags = [False, *(u for _, u, _ in steps), False]
    legs = [leg for _, _, leg in steps] + [last_leg]
    scenario = _line_scenario(kinds, flags, params)
    points = range(len(kinds))
    exact = success_probability(scenario, points, legs)
    assert exact.probability == pytest.approx(
        brute_force_success(scenario, points, legs), abs=1e-12
    )
    assert exact.states <= _state_bound(scenario, list(points))
    if p_success == 1.0:
        deterministic = evaluate_route(scenario, points, [Leg(x) for x in legs]).feasible
        assert exact.probability == (1.0 if deterministic else 0.0)


def test_leg_objects_and_longer_legs() -> None:
    checked = 0
    for scenario, points in _sample():
        legs = straight_legs(scenario, points)
        base = success_probability(scenario, points)
        assert success_probability(scenario, points, legs) == base
        # Flying further (turns) can only raise every error, so never raises the probability.
        longer = [Leg(leg.length * 1.08 + 150.0, arc=leg.length * 0.08 + 150.0) for leg in legs]
        turned = success_probability(scenario, points, longer)
        assert turned.probability <= base.probability + 1e-12
        assert turned.probability == pytest.approx(
            brute_force_success(scenario, points, longer), abs=1e-12
        )
        checked += turned.probability < base.probability
    assert checked > 0


def test_monte_carlo_agrees_with_exact_within_its_interval() -> None:
    uncertain = [(s, p) for s, p in _sample() if 0.0 < success_probability(s, p).probability < 1.0][
        :8
    ]
    assert len(uncertain) == 8
    for i, (scenario, points) in enumerate(uncertain):
        exact = success_probability(scenario, points).probability
        mc = monte_carlo_success(scenario, points, runs=20_000, seed=i, confidence=0.99)
        assert mc.runs == 20_000 and mc.confidence == 0.99
        assert mc.rate == mc.successes / mc.runs
        assert mc.ci_low <= mc.rate <= mc.ci_high
        assert mc.ci_low <= exact <= mc.ci_high, (scenario.name, points, exact, mc)


def test_monte_carlo_is_seeded_and_deterministic_where_it_must_be() -> None:
    scenario, points = next(
        (s, p) for s, p in _sample() if 0.0 < success_probability(s, p).probability < 1.0
    )
    first = monte_carlo_success(scenario, points, runs=5000, seed=7)
    assert monte_carlo_success(scenario, points, runs=5000, seed=7) == first
    others = {monte_carlo_success(scenario, points, runs=5000, seed=s).successes for s in range(5)}
    assert len(others) > 1
    for scenario, points in _sample()[:40]:
        exact = success_probability(scenario, points).probability
        if exact in (0.0, 1.0):
            mc = monte_carlo_success(scenario, points, runs=500, seed=1)
            assert mc.rate == exact


def test_monte_carlo_interval_narrows_with_runs() -> None:
    scenario, points = _sample()[0]
    small = monte_carlo_success(scenario, points, runs=1000, seed=3)
    large = monte_carlo_success(scenario, points, runs=100_000, seed=3)
    assert large.ci_high - large.ci_low < small.ci_high - small.ci_low


def test_brute_force_refuses_many_unreliable_points() -> None:
    params = replace(DATASET1, p_success=0.9)
    n = 21
    scenario = _line_scenario([Kind.A, *[Kind.V] * n, Kind.B], [False, *[True] * n, False], params)
    legs = [1000.0] * (n + 1)
    with pytest.raises(ValueError, match="21 unreliable"):
        brute_force_success(scenario, range(n + 2), legs)
    # The chain itself has no such limit and merges the 2^21 paths.
    result = success_probability(scenario, range(n + 2), legs)
    assert result.states <= n + 1


def test_rejects_malformed_routes() -> None:
    scenario = random_scenario(5, 0)
    with pytest.raises(ValueError):
        success_probability(scenario, [scenario.end, scenario.start])
    with pytest.raises(ValueError):
        success_probability(scenario, [scenario.start, scenario.end], [1.0, 2.0])
    with pytest.raises(ValueError):
        monte_carlo_success(scenario, [scenario.start, scenario.end], runs=0)


# --- the contest's dataset 1 -------------------------------------------------------------------

TABLE3_DATASET1 = [0, 578, 417, 294, 91, 607, 61, 193, 375, 315, 403, 248, 501, 612]


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_paper_route_on_dataset1() -> None:
    scenario = load_scenario(DATA / "dataset1.xlsx", DATASET1.to_dict())
    assert scenario.counts() == {"points": 613, "V": 305, "H": 306, "unreliable": 148}
    points = [scenario.index_of(i) for i in TABLE3_DATASET1]
    assert evaluate_route(scenario, points).feasible
    exact = success_probability(scenario, points)
    assert 0.0 <= exact.probability <= 1.0
    assert exact.probability == pytest.approx(brute_force_success(scenario, points), abs=1e-12)
    # Its four unreliable points are followed by legs short enough that a residual of 5 never
    # breaks a limit; a residual of 15 does, and the chain must still agree with brute force.
    loose = scenario.with_params(fail_residual=15.0)
    worse = success_probability(loose, points)
    assert 0.0 < worse.probability < exact.probability
    assert worse.probability == pytest.approx(brute_force_success(loose, points), abs=1e-12)
    mc = monte_carlo_success(loose, points, runs=20_000, seed=1)
    assert mc.ci_low <= worse.probability <= mc.ci_high
    print(
        f"dataset 1, Table 3 route: P(success) = {exact.probability!r}, "
        f"unreliable on route = {_unreliable_on(scenario, points)}, states = {exact.states}; "
        f"with r = 15: {worse.probability!r}"
    )


def test_wilson_interval_reaches_its_ends_exactly() -> None:
    from gcs_planner.dryrun.confidence import wilson_interval

    for runs in (1, 7, 100, 1000, 12345):
        assert wilson_interval(runs, runs, 0.99)[1] == 1.0
        assert wilson_interval(0, runs, 0.99)[0] == 0.0
        low, high = wilson_interval(runs // 2, runs, 0.99)
        assert 0.0 < low < 0.5 < high < 1.0 or runs == 1
