"""Benchmark of the exact straight-leg search: contest datasets and random scenarios.

    python benchmarks/core.py [--runs 5] [--sizes 300 1500 5000 20000]

Prints medians of several runs and the peak memory of the search (tracemalloc). Ratios against
the obvious implementation are given for the small cases: brute force is out of reach on real
data, so the comparator is the same search without bounds (dominance only).
"""

from __future__ import annotations

import argparse
import statistics
import time
import tracemalloc
from pathlib import Path

from gcs_planner.core.search import straight_front
from gcs_planner.scenario.generate import DATASET1, DATASET2, random_scenario
from gcs_planner.scenario.readers import load_scenario

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "gmcm2019f"


def timed(scenario, runs: int) -> tuple[float, float, float, object]:
    search, total = [], []
    result = None
    for _ in range(runs):
        t0 = time.perf_counter()
        result = straight_front(scenario)
        total.append(time.perf_counter() - t0)
        search.append(result.stats.seconds - result.stats.graph_seconds)
    tracemalloc.start()
    straight_front(scenario)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return statistics.median(search), statistics.median(total), peak / 2**20, result


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--sizes", type=int, nargs="*", default=[300, 1500, 5000, 20000])
    args = ap.parse_args()
    cases = []
    for name, params in (("dataset1", DATASET1), ("dataset2", DATASET2)):
        path = DATA / f"{name}.xlsx"
        if path.exists():
            cases.append((name, load_scenario(path, params.to_dict())))
    for n in args.sizes:
        cases.append((f"random-{n}", random_scenario(n, seed=1, params=DATASET1)))
    head = f"{'scenario':<14} {'points':>7} {'search ms':>10} {'total ms':>9} {'peak MiB':>9}"
    print(f"{head}  front")
    for name, scenario in cases:
        search, total, peak, result = timed(scenario, args.runs)
        front = ", ".join(f"{fp.length:,.1f} m/{fp.corrections}" for fp in result.front)
        print(
            f"{name:<14} {scenario.n:>7} {search * 1e3:>10.1f} {total * 1e3:>9.1f} "
            f"{peak:>9.1f}  {front or 'infeasible'}"
        )


if __name__ == "__main__":
    main()
