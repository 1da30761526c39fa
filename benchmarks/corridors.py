"""Section 10: long corridors, straight legs, three objectives. Routes of 24 and more
corrections whose lengths differ by metres, many of them trading corrections against the
probability of arriving: the case where a proof is hardest. Each row is one ``plan()`` with the
time limit and no label limit (the default), and says whether the front is proven and whether its
fewest-corrections end is the two-objective front's (which it must contain).

    python -m benchmarks.corridors 3000 20000
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

from benchmarks.cases import load_case
from benchmarks.report import proof_text, seconds, table
from gcs_planner.core.planner import plan
from gcs_planner.core.search import straight_front

THREE = ("length", "corrections", "probability")


@dataclass
class CorridorRow:
    points: int
    seconds: float
    labels: int
    open_labels: int
    routes: int
    settled: int
    proven: bool
    largest_gap: float
    complete_below: float | None  # routes missing from the front are at least this long
    fewest: tuple[float, int]  # the three-objective front's fewest-corrections end
    two_objective: tuple[float, int]  # the two-objective front's


def run_corridors(sizes: list[int], time_limit: float) -> list[CorridorRow]:
    rows = []
    for n in sizes:
        scenario = load_case(f"corridor-{n}")
        t0 = time.perf_counter()
        result = plan(scenario, objectives=THREE, time_limit=time_limit)
        took = time.perf_counter() - t0
        two = straight_front(scenario).front[0]
        end = min(result.routes, key=lambda r: (r.corrections, r.length))
        below = result.stats.get("open_bound")
        rows.append(
            CorridorRow(
                n,
                took,
                int(result.stats.get("labels") or 0),
                int(result.stats.get("open_labels") or 0),
                len(result.routes),
                sum(result.proven()),
                result.optimal,
                max(result.gaps(), default=0.0),
                below,
                (end.length, end.corrections),
                (two.length, two.corrections),
            )
        )
    return rows


def render(rows: list[CorridorRow]) -> str:
    header = (
        "points",
        "time",
        "labels",
        "open",
        "front routes",
        "proof",
        "fewest-corrections end",
        "two-objective front's",
    )
    out = []
    for r in rows:
        proof = proof_text(r.proven, r.largest_gap, r.settled, r.routes, r.complete_below)
        same = abs(r.fewest[0] - r.two_objective[0]) < 1e-6 and r.fewest[1] == r.two_objective[1]
        out.append(
            (
                f"{r.points:,}",
                seconds(r.seconds),
                f"{r.labels:,}",
                f"{r.open_labels:,}",
                r.routes,
                proof,
                f"{r.fewest[0]:,.1f} m / {r.fewest[1]}" + (" (same)" if same else " (DIFFERS)"),
                f"{r.two_objective[0]:,.1f} m / {r.two_objective[1]}",
            )
        )
    return table(header, out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sizes", nargs="*", type=int, default=[3000, 20000])
    ap.add_argument("--time-limit", type=float, default=120.0)
    args = ap.parse_args()
    print(render(run_corridors(args.sizes, args.time_limit)))


if __name__ == "__main__":
    main()
