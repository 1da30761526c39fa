"""The straight-leg search queues partial routes by their least continuation that no found route
dominates (``_Incumbents.least_open``): a change of order, which must change neither the front
nor what a search cut short claims."""

from __future__ import annotations

import math

import numpy as np
from support.scenarios import long_corridor_scenario, uncertain_straight_scenario
from support.straight_walk import walked_straight_front

from gcs_planner.core.bnb import Found, bnb_front
from gcs_planner.core.bnb.incumbents import _Incumbents


def test_least_open_is_infinite_exactly_when_covered_and_bounds_every_open_continuation() -> None:
    rng = np.random.default_rng(5)
    checked = 0
    for _ in range(3000):
        kmax = int(rng.integers(0, 8))
        inc = _Incumbents(kmax)
        for _ in range(int(rng.integers(0, 6))):
            inc.add(
                Found(
                    float(rng.uniform(90, 110)),
                    int(rng.integers(0, kmax + 1)),
                    float(rng.choice([1.0, 0.8, 0.64, 0.5])),
                    (),
                )
            )
        k = int(rng.integers(0, kmax + 2))
        to_go = (
            None
            if rng.random() < 0.05
            else np.sort(rng.uniform(0, 60, int(rng.integers(1, 10))))[::-1].copy()
        )
        length = float(rng.uniform(40, 80))
        mass = float(rng.choice([1.0, 0.8, 0.64, 0.3]))
        least = inc.least_open(length, k, to_go, mass)
        assert (least == math.inf) == inc.covers(length, k, to_go, mass)
        if to_go is not None:
            best = inc.best(mass)
            for m in range(min(len(to_go), kmax - k + 1)):
                if length + to_go[m] < best[k + m]:
                    assert least <= length + to_go[m]
                    checked += 1
    assert checked >= 1000


def _exact(front) -> list[tuple[float, int, float]]:
    return [(f.length, f.corrections, f.probability) for f in front]


def test_cut_short_searches_miss_no_route_shorter_than_their_open_bound() -> None:
    """Against enumeration (small scenarios) and the exhausted search (corridors): every exact
    front route a search cut short did not find is at least its open bound long."""
    cut = 0
    cases = [(uncertain_straight_scenario(seed), None) for seed in range(150)]
    cases += [(long_corridor_scenario(seed, n=40), "search") for seed in range(4)]
    for scenario, how in cases:
        if how is None:
            exact = [(w[0], w[1], -w[2]) for w in walked_straight_front(scenario)]
            labels = None
        else:
            full = bnb_front(scenario, probability=True, max_labels=None)
            assert full.optimal
            exact, labels = _exact(full.front), full.labels
        budgets = (1, 2, 4, 8) if labels is None else (labels // 8, labels // 4, labels // 2)
        for budget in budgets:
            res = bnb_front(scenario, probability=True, max_labels=max(1, budget))
            if res.optimal:
                assert len(res.front) == len(exact)
                continue
            cut += 1
            got = _exact(res.front)
            for length, c, p in exact:
                found = any(
                    g[1] == c and abs(g[0] - length) < 1e-6 and abs(g[2] - p) < 1e-9 for g in got
                )
                assert found or length >= res.open_bound - 1e-6, (budget, length, c, p)
    assert cut >= 20
