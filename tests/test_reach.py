"""The reach graph against the definition, pair by pair."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import corridor_scenario, mixed_scenario

from gcs_planner.core.reach import arrival_limits_m, build_reach_graph


@pytest.mark.parametrize("compiled", [False, True], ids=["kdtree", "grid-kernel"])
def test_arcs_are_exactly_the_flyable_legs(compiled: bool) -> None:
    for seed in range(120):
        scenario = (mixed_scenario if seed % 2 else corridor_scenario)(seed, 2, 40)
        graph = build_reach_graph(scenario, compiled=compiled)
        lim_v, lim_h = arrival_limits_m(scenario)
        xyz = scenario.xyz
        want = set()
        for i in range(scenario.n):
            for j in range(scenario.n):
                if i == j or j == scenario.start or i == scenario.end:
                    continue
                d = float(np.linalg.norm(xyz[i] - xyz[j]))
                if d <= min(lim_v[j], lim_h[j]):
                    want.add((i, j))
        got = {}
        for i in range(scenario.n):
            for a in range(graph.indptr[i], graph.indptr[i + 1]):
                got[(i, int(graph.target[a]))] = float(graph.length[a])
        assert set(got) == want, seed
        for (i, j), d in got.items():
            assert abs(d - np.linalg.norm(xyz[i] - xyz[j])) <= 1e-9
