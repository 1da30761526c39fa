"""The compiled backward layers of the cost-to-go give the numpy layers' table, bit for bit."""

from __future__ import annotations

import numpy as np
from helpers import mixed_scenario

from gcs_planner.core.cost_to_go import cost_to_go
from gcs_planner.core.reach import build_reach_graph
from gcs_planner.scenario.generate import random_scenario


def test_compiled_layers_make_the_same_table() -> None:
    cases = [mixed_scenario(seed) for seed in range(40)]
    # Dense and long: many layers, many labels per point, candidates dominated within a layer.
    cases += [
        random_scenario(300, seed, box=(120_000, 15_000, 2_000), unreliable_fraction=0.3)
        for seed in range(3)
    ]
    nonempty = 0
    for scenario in cases:
        graph = build_reach_graph(scenario)
        a = cost_to_go(scenario, graph, compiled=False)
        b = cost_to_go(scenario, graph, compiled=True)
        np.testing.assert_array_equal(a.indptr, b.indptr)
        np.testing.assert_array_equal(a.e_max, b.e_max)
        np.testing.assert_array_equal(a.table, b.table)
        nonempty += a.table.shape[1] > 3
    assert nonempty >= 3
