"""Section 3: every planning mode through the planner's public ``plan()``: straight legs and
turns, two and three objectives, a free heading at A and a given one; each row says whether the
front is proven or, where the default budget ran out, its gaps and how far the front is
complete."""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

from benchmarks.cases import load_case
from benchmarks.report import proof_text, seconds, table
from gcs_planner.core.planner import plan

TURN_RADIUS = 200.0
TWO = ("length", "corrections")
THREE = ("length", "corrections", "probability")
# (turn radius, objectives, heading at A given): every mode. A given heading points from A to B
# (the contest's A and B: the aircraft arrives at A flying roughly towards B).
CASES = (
    (0.0, TWO, False),
    (0.0, THREE, False),
    (TURN_RADIUS, TWO, False),
    (TURN_RADIUS, THREE, False),
    (TURN_RADIUS, TWO, True),
    (TURN_RADIUS, THREE, True),
)


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
    heading: bool = False
    settled: int | None = None  # routes whose "optimal" flag holds
    labels: int | None = None
    complete_below: float | None = None  # the front is complete below this length


def run_turns(specs: list[str], runs: int) -> list[TurnRow]:
    rows = []
    for spec in specs:
        for radius, objectives, heading in CASES:
            scenario = load_case(spec, turn_radius=radius)
            if heading:
                towards_b = scenario.xyz[scenario.end] - scenario.xyz[scenario.start]
                scenario = scenario.with_vehicle(heading_at_a=tuple(map(float, towards_b)))
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
                    heading,
                    sum(result.proven()),
                    result.stats.get("labels"),
                    _complete_below(result.statement),
                )
            )
    return rows


def _complete_below(statement: str) -> float | None:
    """The length below which a front cut short by its budget is complete (from the plan's
    statement; None when proven)."""
    marker = "routes missing from this front are at least "
    if marker not in statement:
        return None
    text = statement.split(marker, 1)[1].split(" m", 1)[0].replace(",", "")
    try:
        return float(text)
    except ValueError:
        return None


def proof(r: TurnRow) -> str:
    """The word "proven", or the largest gap, the routes settled and where completeness ends."""
    if r.optimal is None:
        return "–"
    return proof_text(r.optimal, r.largest_gap, r.settled, r.routes, r.complete_below)


def render(rows: list[TurnRow]) -> str:
    header = (
        "scenario",
        "legs",
        "heading at A",
        "objectives",
        "time (median)",
        "labels",
        "front routes",
        "proof",
        "front (m / corrections[ / probability])",
    )
    return table(
        header,
        [
            (
                r.scenario,
                r.legs,
                "towards B" if r.heading else "free",
                r.objectives,
                seconds(r.seconds),
                r.labels,
                r.routes,
                proof(r),
                r.front or "–",
            )
            for r in rows
        ],
    )
