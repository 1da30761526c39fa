"""Section 6: what a flyable front costs. Both workbooks, straight legs, the tilted-plane cs3d leg
(R = 200 m) and airplane legs (R = 200 m) under climb/descent limits, two and three objectives,
through the planner's public ``plan()``."""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass

from benchmarks.cases import load_case
from benchmarks.report import seconds, table
from gcs_planner.core.planner import plan

TURN_RADIUS = 200.0
LIMITS = ((20.0, 25.0), (15.0, 15.0), (10.0, 12.0))
OBJECTIVES = (("length", "corrections"), ("length", "corrections", "probability"))


@dataclass
class FlyRow:
    scenario: str
    objectives: int
    legs: str
    seconds: float
    routes: int
    proven: bool
    largest_gap: float
    shortest: tuple[float, int]
    certain: float | None  # shortest route with P = 1, when the front has one
    steepest: float  # degrees, over every leg of the front
    helices: int  # helix turns over the front


def _cases() -> list[tuple[str, float, dict]]:
    cases = [("straight", 0.0, {}), ("cs3d", TURN_RADIUS, {"leg_model": "cs3d"})]
    cases.append(("airplane, unlimited climb", TURN_RADIUS, {}))
    for climb, descent in LIMITS:
        limits = {"max_climb_angle": climb, "max_descent_angle": descent}
        cases.append((f"airplane, {climb:g}°/{descent:g}°", TURN_RADIUS, limits))
    return cases


def run_flyable(specs: list[str], runs: int) -> list[FlyRow]:
    rows = []
    for spec in specs:
        for objectives in OBJECTIVES:
            for legs, radius, changes in _cases():
                base = load_case(spec, turn_radius=radius)
                params = {k: v for k, v in changes.items() if k != "leg_model"}
                scenario = base.with_params(**params) if params else base
                if "leg_model" in changes:
                    scenario = scenario.with_vehicle(leg_model=changes["leg_model"])
                times, result = [], None
                for _ in range(runs):
                    t0 = time.perf_counter()
                    result = plan(scenario, objectives=objectives)
                    times.append(time.perf_counter() - t0)
                assert result is not None
                shortest = min(result.routes, key=lambda r: (r.length, r.corrections))
                certain = result.shortest_certain
                legs_all = [s.leg for r in result.routes for s in r.stops[1:]]
                rows.append(
                    FlyRow(
                        spec,
                        len(objectives),
                        legs,
                        statistics.median(times),
                        len(result.routes),
                        result.optimal,
                        max(result.gaps(), default=0.0),
                        (shortest.length, shortest.corrections),
                        None if certain is None else result.routes[certain].length,
                        max(abs(leg.path_angle) for leg in legs_all),
                        sum(leg.helix_turns for leg in legs_all),
                    )
                )
    return rows


def render(rows: list[FlyRow]) -> str:
    base = {(r.scenario, r.objectives): r.shortest[0] for r in rows if r.legs == "straight"}
    header = (
        "scenario",
        "obj.",
        "legs",
        "shortest route (m / corr.)",
        "vs straight",
        "shortest certain (m)",
        "front",
        "proof",
        "steepest leg",
        "helix turns",
        "time",
    )
    body = []
    for r in rows:
        ref = base.get((r.scenario, r.objectives))
        body.append(
            (
                r.scenario,
                r.objectives,
                r.legs,
                f"{r.shortest[0]:,.1f} / {r.shortest[1]}",
                f"+{100 * (r.shortest[0] / ref - 1):.2f} %" if ref else "–",
                f"{r.certain:,.1f}" if r.certain is not None else "none found",
                r.routes,
                "proven" if r.proven else f"not proven (gap ≤ {r.largest_gap:,.0f} m)",
                f"{r.steepest:.1f}°",
                r.helices,
                seconds(r.seconds),
            )
        )
    return table(header, body)
