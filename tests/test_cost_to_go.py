"""The cost-to-go per number of further corrections against enumeration of every walk."""

from __future__ import annotations

import itertools

import numpy as np
from helpers import mixed_scenario

from gcs_planner.core.cost_to_go import cost_to_go
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
