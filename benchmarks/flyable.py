"""Section 6: what a flyable front costs. Both workbooks, straight legs, the tilted-plane cs3d leg
(R = 200 m) and airplane legs (R = 200 m) under climb/descent limits, two and three objectives,
through the planner's public ``plan()``."""

from __future__ import annotations

import argparse
import math
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
    unsettled: int  # front routes not proven to be on the front with nothing missing beside them
    complete_below: float  # routes missing from the front are at least this long (inf: none)
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


def run_flyable(
    specs: list[str],
    runs: int,
    objectives_counts: tuple[int, ...] = (2, 3),
    legs_wanted: tuple[str, ...] | None = None,
) -> list[FlyRow]:
    rows = []
    for spec in specs:
        for objectives in OBJECTIVES:
            if len(objectives) not in objectives_counts:
                continue
            for legs, radius, changes in _cases():
                if legs_wanted is not None and not any(w in legs for w in legs_wanted):
                    continue
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
                        len(result.routes) - sum(result.settled or (True,) * len(result.routes)),
                        result.stats.get("open_bound") or math.inf,
                        (shortest.length, shortest.corrections),
                        None if certain is None else result.routes[certain].length,
                        max(abs(leg.path_angle) for leg in legs_all),
                        sum(leg.helix_turns for leg in legs_all),
                    )
                )
    return rows


def _proof(r: FlyRow) -> str:
    """'proven', or what is known: the largest gap, and (a gap of 0 alone would read as a
    proof) how many routes are unsettled and below which length the front is complete."""
    if r.proven:
        return "proven"
    text = f"not proven (gap ≤ {r.largest_gap:,.0f} m; {r.unsettled} of {r.routes} unsettled"
    if math.isfinite(r.complete_below):
        text += f"; complete below {r.complete_below:,.0f} m"
    return text + ")"


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
                _proof(r),
                f"{r.steepest:.1f}°",
                r.helices,
                seconds(r.seconds),
            )
        )
    return table(header, body)


def main(argv: list[str] | None = None) -> None:
    """This section alone: ``python -m benchmarks.flyable [--scenarios ...] [--objectives ...]``."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.flyable", description=__doc__)
    ap.add_argument("--scenarios", nargs="+", default=["dataset1", "dataset2"])
    ap.add_argument("--objectives", type=int, nargs="+", choices=(2, 3), default=[2, 3])
    ap.add_argument(
        "--legs",
        nargs="+",
        default=None,
        help="rows whose 'legs' column contains one of these (e.g. cs3d 15°; default: all)",
    )
    ap.add_argument("--runs", type=int, default=1, help="runs per row (median time)")
    args = ap.parse_args(argv)
    if args.runs < 1:
        ap.error("--runs must be >= 1")
    legs = None if args.legs is None else tuple(args.legs)
    print(render(run_flyable(args.scenarios, args.runs, tuple(args.objectives), legs)))


if __name__ == "__main__":
    main()
