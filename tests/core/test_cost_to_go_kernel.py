"""The compiled backward layers of the cost-to-go give the numpy layers' table, bit for bit."""

from __future__ import annotations

import numba
import numpy as np
from support.scenarios import mixed_scenario

from gcs_planner.core.cost_to_go import cost_to_go
from gcs_planner.core.reach import build_reach_graph
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Kind


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


def test_compiled_layers_make_the_same_table_over_expanded_graphs(monkeypatch) -> None:
    """The graphs whose nodes are not the points (the pairs of ``pair_bounds``, the copies per
    forced failure of ``failure_bounds``, with their own V flags and start errors), which the
    compiled layers serve on large maps."""
    from support.scenarios import probed_scenario

    from gcs_planner.core import cost_to_go as module
    from gcs_planner.core.failure_bounds import failure_bounds
    from gcs_planner.core.pair_bounds import pair_bounds
    from gcs_planner.geometry.legs import scenario_leg_model

    expanded = 0
    for seed in range(6):
        scenario = probed_scenario(seed, "airplane")
        graph = build_reach_graph(scenario)
        pairs = pair_bounds(scenario, graph, scenario_leg_model(scenario))
        assert pairs is not None
        is_v = scenario.kind[pairs.point] == Kind.V
        for over in (graph, pairs.graph):
            tables = []
            for compiled in (False, True):
                monkeypatch.setattr(module, "use_compiled", lambda n, c, on=compiled: on)
                if over is graph:  # the copies per forced failure
                    bounds = failure_bounds(scenario, graph)
                    assert bounds is not None
                    tables.append(bounds.G)
                else:
                    tables.append(module.cost_to_go(scenario, pairs.graph, is_v=is_v))
            a, b = tables
            np.testing.assert_array_equal(a.indptr, b.indptr)
            np.testing.assert_array_equal(a.e_max, b.e_max)
            np.testing.assert_array_equal(a.table, b.table)
            expanded += a.table.shape[0] > scenario.n
    assert expanded >= 12


def test_layers_fanned_on_threads_make_the_same_table(monkeypatch) -> None:
    """The labels of a layer cut into slices fanned on threads, each slice with its own copy of
    the summaries, give the single thread's table bit for bit, whatever the number of slices
    (a slice drops fewer candidates early; the filter after drops the rest)."""
    from gcs_planner.core import cost_to_go as module

    monkeypatch.setattr(module, "SLICE_LABELS", 1)
    sliced = 0
    for seed in range(4):
        scenario = random_scenario(300, seed, box=(120_000, 15_000, 2_000))
        graph = build_reach_graph(scenario)
        tables = []
        for threads in (1, 2, 3, 7):
            monkeypatch.setattr(numba, "get_num_threads", lambda t=threads: t)
            tables.append(cost_to_go(scenario, graph, compiled=True))
        for other in tables[1:]:
            np.testing.assert_array_equal(tables[0].indptr, other.indptr)
            np.testing.assert_array_equal(tables[0].e_max, other.e_max)
            np.testing.assert_array_equal(tables[0].table, other.table)
        sliced += tables[0].layers > 3
    assert sliced >= 2
