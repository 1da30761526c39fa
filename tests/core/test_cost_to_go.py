"""The cost-to-go per number of further corrections against enumeration of every walk."""

from __future__ import annotations

import itertools

import numpy as np
from support.scenarios import mixed_scenario

from gcs_planner.core.cost_to_go import _suffix_minima, cost_to_go
from gcs_planner.core.reach import build_reach_graph
from gcs_planner.scenario.model import Kind


def shortest_walk(scenario, j: int, e: float, m: int) -> float:
    """Least straight length from j (just corrected, carrying e metres on the component j did
    not reset) to B through at most m further correction points, revisits allowed."""
    p = scenario.params
    xyz = scenario.xyz
    inner = [i for i in range(scenario.n) if scenario.kind[i] in (Kind.V, Kind.H)]
    best = np.inf
    for count in range(m + 1):
        for chain in itertools.product(inner, repeat=count):
            own_v = scenario.kind[j] == Kind.V
            v, h = (0.0, e) if own_v else (e, 0.0)
            here, length, ok = j, 0.0, True
            for t in (*chain, scenario.end):
                d = float(np.linalg.norm(xyz[t] - xyz[here]))
                v, h = v + d, h + d
                v_lim, h_lim = p.limits_m(Kind(int(scenario.kind[t])))
                if d == 0 or v > v_lim or h > h_lim:
                    ok = False
                    break
                if scenario.kind[t] == Kind.V:
                    v = 0.0
                elif scenario.kind[t] == Kind.H:
                    h = 0.0
                here, length = t, length + d
            if ok:
                best = min(best, length)
    return best


def test_bound_per_number_of_corrections_is_the_shortest_walk() -> None:
    checked = finite = 0
    for seed in range(40):
        scenario = mixed_scenario(seed, n_min=2, n_max=4)
        graph = build_reach_graph(scenario)
        G = cost_to_go(scenario, graph)
        reach = scenario.params.reach_m
        for j in range(scenario.n):
            if scenario.kind[j] not in (Kind.V, Kind.H):
                continue
            for e in np.linspace(0.0, reach, 5):
                table = G.by_corrections(j, float(e))
                for m in range(4):
                    want = shortest_walk(scenario, j, float(e), m)
                    got = np.inf if table is None else float(table[min(m, len(table) - 1)])
                    assert got == want or abs(got - want) <= 1e-6 * max(1.0, want), (seed, j, e, m)
                    checked += 1
                    finite += np.isfinite(want)
                if table is not None:
                    assert np.all(np.diff(table) <= 0)  # more corrections never cost more
                    assert G(j, float(e)) == table[-1]
    assert checked > 500 and finite > 100


def test_a_table_cut_short_keeps_its_layers_and_bounds_the_rest_from_below() -> None:
    """``stop`` ends the layers: the columns made are the full table's, the last one is no
    larger than the full table anywhere beyond, and no point B can be reached from is lost."""
    cut = compared = 0
    for seed in range(60):
        scenario = mixed_scenario(seed, n_min=4, n_max=9)
        graph = build_reach_graph(scenario)
        full = cost_to_go(scenario, graph)
        assert full.cut_at is None
        for layers in (0, 1, 2, 3):
            part = cost_to_go(scenario, graph, stop=_after(layers))
            if part.cut_at is None:  # converged before the cut
                np.testing.assert_array_equal(part.table, full.table)
                continue
            cut += 1
            assert part.cut_at == layers and part.layers == layers + 1
            for j in range(scenario.n):
                if j == scenario.end:
                    continue
                for e in np.linspace(0.0, scenario.params.reach_m, 7):
                    want = full.by_corrections(j, float(e))
                    got = part.by_corrections(j, float(e))
                    assert got is not None  # never "B out of reach" for want of layers
                    to_b = float(graph.to_end[j])
                    for m in range(scenario.n):
                        w = np.inf if want is None else float(want[min(m, len(want) - 1)])
                        g = float(got[min(m, len(got) - 1)])
                        if m < layers:
                            assert g == w, (seed, j, e, m)
                        else:
                            assert g <= w and g <= to_b, (seed, j, e, m)
                        compared += 1
    assert cut >= 80 and compared > 5_000


def _after(layers: int):
    """A ``stop`` that ends the table after ``layers`` layers (it is asked before each)."""
    asked = itertools.count(0)
    return lambda: next(asked) >= layers


def test_suffix_minima_by_doubling_equal_the_minima_row_by_row() -> None:
    """The table's minimum over every label of a point allowing at least as much error
    (``_suffix_minima``) against one running minimum per point, on random tables with points of
    0 to 40 rows and infinite entries."""
    rng = np.random.default_rng(5)
    for _ in range(300):
        counts = rng.integers(0, 40, int(rng.integers(1, 30)))
        indptr = np.concatenate([[0], np.cumsum(counts)])
        node = np.repeat(np.arange(len(counts)), counts)
        table = rng.choice([1.0, 2.5, 3.0, 7.0, np.inf], size=(int(indptr[-1]), 3))
        expected = table.copy()
        for j in np.flatnonzero(counts):
            lo, hi = indptr[j], indptr[j + 1]
            expected[lo:hi] = np.minimum.accumulate(expected[lo:hi][::-1], axis=0)[::-1]
        _suffix_minima(table, indptr[node + 1])
        assert np.array_equal(table, expected)
