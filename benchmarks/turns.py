"""Section 3: turns and uncertain corrections through the planner's public ``plan()``."""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

from benchmarks.cases import load_case
from benchmarks.report import seconds, table
from gcs_planner.core.planner import plan

TURN_RADIUS = 200.0
OBJECTIVE_SETS = (("length", "corrections"), ("length", "corrections", "probability"))


@dataclass
class TurnRow:
    scenario: str
    objectives: str
    seconds: float | None
    routes: int | None
    optimal: bool | None
    largest_gap: float | None  # metres between a front route and its proven lower bound
    front: str = ""
    error: str = ""


def run_turns(specs: list[str], runs: int) -> list[TurnRow]:
    rows = []
    for spec in specs:
        scenario = load_case(spec, turn_radius=TURN_RADIUS)
        for objectives in OBJECTIVE_SETS:
            name = ", ".join(objectives)
            times, result = [], None
            try:
                for _ in range(runs):
                    t0 = time.perf_counter()
                    result = plan(scenario, objectives=objectives)
                    times.append(time.perf_counter() - t0)
            except Exception as exc:  # the lead is reworking plan(): report, do not stop
                rows.append(TurnRow(spec, name, None, None, None, None, error=repr(exc)))
                continue
            front = "; ".join(
                f"{r.length:,.0f}/{r.corrections}"
                + (f"/p={r.probability:.3f}" if "probability" in objectives else "")
                for r in result.routes
            )
            rows.append(
                TurnRow(
                    spec,
                    name,
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
                r.objectives,
                seconds(r.seconds) if r.error == "" else r.error,
                r.routes,
                r.optimal,
                f"{r.largest_gap:.3g}" if r.largest_gap is not None else None,
                r.front or "–",
            )
            for r in rows
        ],
    )
