"""The fan prefilter of the branch and bound may only be weaker than the per-leg test."""

from __future__ import annotations

import numpy as np
from support.scenarios import mixed_scenario

from gcs_planner.core.cost_to_go import cost_to_go
from gcs_planner.core.prefilter import FanBound, covered_fan
from gcs_planner.core.reach import build_reach_graph


def test_fan_rows_never_exceed_the_cost_to_go() -> None:
    rng = np.random.default_rng(0)
    checked = 0
    for seed in range(30):
        scenario = mixed_scenario(seed)
        G = cost_to_go(scenario, build_reach_graph(scenario))
        fan = FanBound(G, scenario.n)
        j = rng.integers(0, scenario.n, 200)
        # Errors at, just around and between the labels' limits: where rounding would bite.
        pick = rng.integers(0, max(1, len(G.e_max)), 200)
        e = np.where(
            rng.random(200) < 0.5,
            G.e_max[pick] if len(G.e_max) else 0.0,
            rng.uniform(0, 30_000, 200),
        ) + rng.choice([-1e-9, 0.0, 1e-9], 200)
        e = np.maximum(e, 0.0)
        rows = fan.rows(j, e)
        for r, jj, ee in zip(rows, j, e):
            exact = G.by_corrections(int(jj), float(ee))
            if exact is None:
                continue
            assert np.all(r <= exact), (seed, jj, ee)
            checked += 1
    assert checked >= 500


def test_covered_fan_is_the_all_m_test() -> None:
    best = np.array([np.inf, 100.0, 90.0, 80.0])
    rows = np.array([[50.0, 40.0, 30.0], [np.inf, np.inf, np.inf], [20.0, 10.0, 5.0]])
    got = covered_fan(np.array([60.0, 0.0, 60.0]), 1, rows, best)
    # 60+50 >= 100, 60+40 >= 90, 60+30 >= 80: covered; no route to B: covered; 80 < 100: open.
    assert got.tolist() == [True, True, False]
    # No further correction allowed: every extension is covered.
    assert covered_fan(np.array([0.0]), 4, rows[:1], best).tolist() == [True]
