"""Focusing the straight-leg search on the ellipsoid of the fewest-corrections route changes no
front: the fewest corrections over walks bound every route's, and the focused front equals the
search over all points on many random scenarios, including those where the first ellipsoid is
too thin and those where only walks that revisit points are shortest."""

from __future__ import annotations

import numpy as np
import pytest
from support.scenarios import corridor_scenario, mixed_scenario

from gcs_planner.baselines.brute import brute_force_front
from gcs_planner.core import straight_search
from gcs_planner.core.kernel import fewest_corrections
from gcs_planner.core.reach import arrival_limits_m, build_reach_graph
from gcs_planner.core.route import evaluate_route
from gcs_planner.core.search import FOCUS_SLACK, straight_front
from gcs_planner.core.straight_search import search_front
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Kind, Parameters, Scenario


def fewest(scenario: Scenario) -> tuple[int, float, list[int]]:
    lim_v, lim_h = arrival_limits_m(scenario)
    reach = np.minimum(lim_v, lim_h)
    inner = reach[(np.arange(scenario.n) != scenario.end) & np.isfinite(reach)]
    to_end = np.linalg.norm(scenario.xyz - scenario.xyz[scenario.end], axis=1)
    k, length, walk = fewest_corrections(
        scenario.xyz,
        lim_v,
        lim_h,
        scenario.kind == Kind.V,
        to_end,
        scenario.start,
        scenario.end,
        float(inner.max()),
    )
    return int(k), float(length), walk.tolist()


def dense_scenario(seed: int, max_points: int = 80) -> Scenario:
    """Tens of points (20 to 250 drawn, at most ``max_points``: the same draws whatever it is)
    with random limits: fronts of several routes, and ellipsoids that leave many points out.
    At most 80: as many focused searches, and as many grown ellipsoids, as the test below asks
    for, at less than two thirds of the work of up to 250."""
    rng = np.random.default_rng(seed)
    n = min(int(rng.integers(20, 250)), max_points)
    a1, a2, b1, b2 = rng.uniform(5, 30, 4)
    params = Parameters(a1, a2, b1, b2, rng.uniform(5, 30), 0.001, turn_radius=0.0)
    length = rng.uniform(20_000, 80_000)
    box = (length, length * rng.uniform(0.2, 1.0), length * rng.uniform(0.02, 0.2))
    return random_scenario(n, seed, params=params, box=box)


@pytest.mark.parametrize(
    ("make", "seeds"), [(mixed_scenario, 150), (corridor_scenario, 600), (dense_scenario, 150)]
)
def test_fewest_corrections_is_the_walk_relaxations_and_bounds_simple_routes(make, seeds) -> None:
    feasible = 0
    for seed in range(seeds):
        scenario = make(seed)
        k, length, walk = fewest(scenario)
        # The search itself (straight_front without the reason an empty front is given, which
        # this test does not read).
        walks = search_front(scenario, max_rounds=1, focus=False).front
        if not walks:
            assert k == -1, seed
            continue
        feasible += 1
        # The layered search over walks finds its fewest corrections first.
        assert k == walks[0].corrections, seed
        # The walk returned is one: feasible, with that many corrections and that length.
        route = evaluate_route(scenario, walk)
        assert route.feasible, (seed, walk)
        assert route.corrections == k
        assert route.length == pytest.approx(length, abs=1e-6)
        if scenario.n <= 9:
            simple = brute_force_front(scenario)
            assert not simple or k <= min(c for _, c, _ in simple), seed
    assert feasible >= 30


# The two ways of focusing the test below compares (``bounds_are_chords`` as it is, or False).
WAYS = ("walk-bound", "ellipsoids")


@pytest.mark.parametrize(
    ("make", "seeds"), [(dense_scenario, 120), (corridor_scenario, 600), (mixed_scenario, 120)]
)
def test_focused_front_equals_the_search_over_all_points(make, seeds, monkeypatch) -> None:
    """Both ways of focusing: bounded by the fewest-corrections walk where it is a route
    ("walk-bound"), and by ellipsoids of growing slack (what runs where it is not, made to run
    everywhere here: "ellipsoids"), each against one search over all points per scenario."""
    focused = dict.fromkeys(WAYS, 0)
    grown = dict.fromkeys(WAYS, 0)
    revisits = dict.fromkeys(WAYS, 0)
    for seed in range(seeds):
        scenario = make(seed)
        rng = np.random.default_rng(seed + 7)
        kw = {}
        if seed % 4 == 1:
            kw["max_rounds"] = 1  # walks: the floor the three-objective search uses
        if seed % 5 == 2:
            kw["max_corrections"] = int(rng.integers(1, 8))
        # The reference: the search over all points (its empty fronts' reasons are not read).
        whole = search_front(scenario, focus=False, **kw)
        for way in WAYS:
            with monkeypatch.context() as patch:
                if way == "ellipsoids":
                    patch.setattr(straight_search, "bounds_are_chords", lambda scenario: False)
                # Given the scenario's own graph (as the three-objective search's floor is), or
                # not.
                graph = build_reach_graph(scenario) if seed % 3 == 0 else None
                ours = straight_front(scenario, graph, focus=True, **kw)
            what = (seed, way)
            assert [(fp.corrections, fp.points) for fp in ours.front] == [
                (fp.corrections, fp.points) for fp in whole.front
            ], what
            np.testing.assert_allclose(
                [fp.length for fp in ours.front],
                [fp.length for fp in whole.front],
                atol=1e-6,
                err_msg=str(what),
            )
            assert (ours.why_infeasible is None) == bool(ours.front), what
            revisits[way] += bool(ours.stats.critical)
            if ours.stats.points < scenario.n:
                focused[way] += 1
                ab = float(
                    np.linalg.norm(scenario.xyz[scenario.start] - scenario.xyz[scenario.end])
                )
                if whole.front[0].length > ab * (1 + FOCUS_SLACK) + 1.0:
                    grown[way] += 1  # the first ellipsoid missed the fewest-corrections route
    # The sample must exercise what it claims to: searches focused, some after growing.
    for way in WAYS:
        if make is dense_scenario:
            assert focused[way] >= 25 and (way == "walk-bound" or grown[way] >= 10), (
                way, focused, grown,
            )  # fmt: skip
        if make is corridor_scenario:
            assert focused[way] >= 15 and revisits[way] >= 1, (way, focused, revisits)


def test_contest_box_is_searched_over_a_few_percent_of_its_points() -> None:
    """The contest's 100 km box with 2,000 points: the front over all points, from a search
    over the fifth of them that can lie on it."""
    scenario = random_scenario(2000, 3)
    whole = straight_front(scenario, focus=False)
    ours = straight_front(scenario, focus=True)
    assert [(fp.corrections, fp.points) for fp in ours.front] == [
        (fp.corrections, fp.points) for fp in whole.front
    ]
    assert ours.stats.points < scenario.n // 4
