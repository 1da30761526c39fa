"""The reach graph against the definition, pair by pair."""

from __future__ import annotations

import numpy as np
import pytest
from support.scenarios import corridor_scenario, mixed_scenario

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


@pytest.mark.parametrize("block", [7, 1000])
def test_bounded_arcs_by_blocks_equal_the_whole_graph_at_once(monkeypatch, block: int) -> None:
    """Airplane legs raise each chord to its lower bound and drop arcs that then reach no
    limit, a block of source points at a time (memory): the same graph as all arcs at once."""
    import gcs_planner.core.reach as reach
    from gcs_planner.geometry.legs import scenario_leg_model
    from gcs_planner.scenario.generate import DATASET1, random_scenario

    dropped = 0
    for seed in range(6):
        scenario = random_scenario(300, seed, params=DATASET1, box=(100e3, 100e3, 10e3))
        scenario = scenario.with_params(
            turn_radius=[0.0, 200.0][seed % 2],
            max_climb_angle=[8.0, 15.0, 30.0][seed % 3],
            max_descent_angle=[8.0, 15.0, 90.0][seed % 3],
        )
        chords = reach._chord_graph(scenario, None)
        model = scenario_leg_model(scenario)
        src = np.repeat(np.arange(chords.n), chords.degree())
        bound = model.lower_bounds(np.zeros(3), scenario.xyz[chords.target] - scenario.xyz[src])
        keep = bound <= np.minimum(chords.lim_v, chords.lim_h)[chords.target]
        indptr = np.zeros(chords.n + 1, dtype=np.int64)
        np.cumsum(np.bincount(src[keep], minlength=chords.n), out=indptr[1:])
        monkeypatch.setattr(reach, "_BLOCK_ARCS", block)
        graph = reach._bounded(chords, scenario.xyz, model)
        assert np.array_equal(graph.indptr, indptr)
        assert np.array_equal(graph.target, chords.target[keep])
        assert np.array_equal(graph.length, bound[keep])
        dropped += int((~keep).sum())
    assert dropped > 1000
