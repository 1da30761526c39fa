"""Section 3: turns and uncertain corrections through the planner's public ``plan()``."""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

from benchmarks.cases import load_case
from benchmarks.report import seconds, table
from gcs_planner.core.planner import plan

TURN_RADIUS = 200.0
TWO = ("length", "corrections")
THREE = ("length", "corrections", "probability")
# (turn radius, objectives): the turns issue's two fronts, and the three-objective front with
# straight legs (where dominance over error-state distributions proves it).
CASES = ((TURN_RADIUS, TWO), (TURN_RADIUS, THREE), (0.0, THREE))


@dataclass
class TurnRow:
    scenario: str
    legs: str
    objectives: str
    seconds: float | None
    routes: int | None
    optimal: bool | None
    largest_gap: float | None  # metres between a front route and its proven lower bound
    front: str = ""


def run_turns(specs: list[str], runs: int) -> list[TurnRow]:
    rows = []
    for spec in specs:
        for radius, objectives in CASES:
            scenario = load_case(spec, turn_radius=radius)
            times, result = [], None
            for _ in range(runs):
                t0 = time.perf_counter()
                result = plan(scenario, objectives=objectives)
                times.append(time.perf_counter() - t0)
            front = "; ".join(
                f"{r.length:,.0f}/{r.corrections}"
                + (f"/p={r.probability:.3f}" if "probability" in objectives else "")
                for r in result.routes
            )
            rows.append(
                TurnRow(
                    spec,
                    f"R = {radius:g} m" if radius else "straight",
                    ", ".join(objectives),
                    statistics.median(times),
                    len(result.routes),
                    result.optimal,
                    max(result.gaps(), default=0.0),
                    front,
                )
            )
    return rows


def render(rows: list[TurnRow]) -> str:
    header = (
        "scenario",
        "legs",
        "objectives",
        "time (median)",
        "front routes",
        "optimal flag",
        "largest gap (m)",
        "front (m / corrections[ / probability])",
    )
    return table(
        header,
        [
            (
                r.scenario,
                r.legs,
                r.objectives,
                seconds(r.seconds),
                r.routes,
                r.optimal,
                f"{r.largest_gap:.3g}" if r.largest_gap is not None else None,
                r.front or "–",
            )
            for r in rows
        ],
    )
