"""The task a worker runs for one cell: load or generate the scenario, plan it, optionally
dry-run the chosen route, and return the cell's rows (one per front route).

It never raises for a cell's own failure: a bad scenario file, an infeasible scenario or a bug
in the planner becomes one row with ``status`` and ``error``, so one cell cannot stop a sweep.
The same function is what the serial benchmark and the tests call directly, which is what makes
"the sweep gives the same rows as planning each cell alone" a comparison of like with like.
"""

from __future__ import annotations

import dataclasses
import math
import os
import socket
import time
from datetime import datetime, timezone

from gcs_planner.aircraft.profile import turn_radius_from
from gcs_planner.errors import InfeasibleError
from gcs_planner.scenario.model import Scenario
from gcs_planner.scenario.readers import PARAMETER_KEYS
from gcs_planner.sweep.cells import Cell
from gcs_planner.sweep.spec import BASE_PARAMETERS, FileSource, GeneratedSource

# Every planning parameter of a scenario (the reserve included), swept alike on files and on
# generated scenarios, each a column of the table.
PARAMETER_FIELDS = PARAMETER_KEYS


def load_cell_scenario(cell: Cell) -> Scenario:
    """The cell's scenario with its values applied, read or generated here (on the worker)."""
    source = cell.source
    if isinstance(source, FileSource):
        from gcs_planner.scenario.readers import load_scenario

        scenario = load_scenario(source.path, cell.overrides)
    else:
        scenario = _generated(source, cell.overrides)
    environment = cell.environment
    return dataclasses.replace(scenario, **environment) if environment else scenario


def _generated(source: GeneratedSource, overrides: dict[str, object]) -> Scenario:
    from gcs_planner.scenario.generate import random_scenario

    scenario = random_scenario(
        source.corrections,
        source.seed,
        params=BASE_PARAMETERS[source.parameters],
        box=source.box,
        unreliable_fraction=source.unreliable_fraction,
    )
    params = {k: float(v) for k, v in overrides.items() if k in PARAMETER_FIELDS}  # type: ignore[arg-type]
    vehicle: dict[str, object] = {}
    if "leg_model" in overrides:
        vehicle["leg_model"] = overrides["leg_model"]
    if "cruise_airspeed" in overrides:
        vehicle["cruise_airspeed"] = float(overrides["cruise_airspeed"])  # type: ignore[arg-type]
    if "max_bank_angle" in overrides:
        # As a scenario file's [vehicle]: airspeed and bank give the radius.
        speed = float(vehicle.get("cruise_airspeed", scenario.cruise_airspeed))  # type: ignore[arg-type]
        params["turn_radius"] = turn_radius_from(speed, float(overrides["max_bank_angle"]))  # type: ignore[arg-type]
        vehicle["radius_source"] = "airspeed and bank"
    if params:
        scenario = scenario.with_params(**params)
    if vehicle:
        scenario = scenario.with_vehicle(**vehicle)
    return scenario


def _compiled_legs() -> None:
    """numba loaded before the cell plans, so that every cell flies its airplane legs compiled
    from the first label (core/bnb/search.py) whatever the process planned before: a loop, a
    forked worker and a restarted one give the same rows to the last bit, and a contest-sized
    cell plans in about 0.1 s rather than 0.15 s. (The command line's `plan` loads numba only
    for a search that proves long: it plans once, and a short search should start fast.)"""
    import numba  # noqa: F401


def objectives_for(scenario: Scenario, cell: Cell) -> tuple[str, ...]:
    """The cell's objectives, or `gcs-planner plan`'s default for this scenario."""
    objectives = cell.planned_objectives
    if objectives is None:
        objectives = ("length", "corrections")
        if scenario.unreliable.any():
            objectives += ("probability",)
    if cell.choice == "most-reliable" and "probability" not in objectives:
        objectives += ("probability",)
    return tuple(objectives)


def run_cell(cell: Cell) -> list[dict]:
    """Plan ``cell`` and return its rows; failures are rows too (see the module's docstring)."""
    started = time.perf_counter()
    base = cell_inputs(cell)
    try:
        scenario = load_cell_scenario(cell)
        base.update(_scenario_inputs(scenario))
        objectives = objectives_for(scenario, cell)
        base["objectives"] = ",".join(objectives)
        from gcs_planner.core.planner import plan

        _compiled_legs()
        t0 = time.perf_counter()
        result = plan(
            scenario,
            objectives=objectives,
            choice=cell.choice,
            max_labels=cell.max_labels,
            time_limit=cell.time_limit,
        )
        plan_seconds = time.perf_counter() - t0
        replay = _replay(result, cell) if cell.dry_run_runs > 0 else {}
    except InfeasibleError as exc:
        return [finish_row({**base, "status": "infeasible", "error": str(exc)}, started)]
    except Exception as exc:  # a cell's failure is data: the sweep goes on
        return [finish_row({**base, "status": "error", "error": _describe(exc)}, started)]
    rows = []
    for i, (route, gap, bound) in enumerate(zip(result.routes, result.gaps(), result.lower_bounds)):
        row = {
            **base,
            "status": "ok",
            "error": "",
            "front_size": len(result.routes),
            "route": i,
            "chosen": i == result.chosen,
            "length": route.length,
            "corrections": route.corrections,
            "probability": route.probability,
            "proven": result.optimal,
            "gap": gap,
            "lower_bound": bound if math.isfinite(bound) else None,
            "route_ids": " ".join(route.ids()),
            "plan_seconds": plan_seconds,
        }
        if i == result.chosen:
            row.update(replay)
        rows.append(row)
    return [finish_row(row, started) for row in rows]


def _replay(result, cell: Cell) -> dict:
    """The optional dry-run step: the chosen route replayed ``dry_run_runs`` times on the mock
    vehicle, whose landmark database is the scenario loaded a second time (as `dry-run` does)."""
    from gcs_planner.dryrun.run import dry_run

    landmarks = load_cell_scenario(cell)
    report = dry_run(result, landmarks, runs=cell.dry_run_runs, seed=cell.dry_run_seed)
    low, high = report.success_ci or (None, None)
    return {
        "dry_run_runs": report.runs,
        "dry_run_verified": report.verified,
        "dry_run_arrived": report.arrived,
        "dry_run_success_rate": report.success_rate,
        "dry_run_ci_low": low,
        "dry_run_ci_high": high,
        "dry_run_confidence": report.confidence,
    }


def cell_inputs(cell: Cell) -> dict:
    source = cell.source
    row: dict = {"cell": cell.index, "cell_key": cell.key}
    if isinstance(source, FileSource):
        row["scenario"] = os.path.basename(source.path)
        row["source"] = source.path
    else:
        row["scenario"] = f"random-{source.corrections}-{source.seed}"
        row["source"] = (
            f"random(corrections={source.corrections}, seed={source.seed}, "
            f"box={'x'.join(f'{b:g}' for b in source.box)}, parameters={source.parameters}, "
            f"unreliable_fraction={source.unreliable_fraction:g})"
        )
        row["seed"] = source.seed
        row["unreliable_fraction"] = source.unreliable_fraction
    for key, value in cell.values:
        row[key] = ",".join(value) if key == "objectives" else value  # type: ignore[arg-type]
    row["choice"] = cell.choice
    row["max_labels"] = cell.max_labels
    row["time_limit"] = cell.time_limit
    # A failed or infeasible cell has no chosen route: False, never null, so that a boolean
    # mask (pandas' df[df.chosen]) works on any table.
    row["chosen"] = False
    return row


def _scenario_inputs(scenario: Scenario) -> dict:
    counts = scenario.counts()
    row: dict = {
        "scenario": scenario.name,
        "points": counts["points"],
        "unreliable_points": counts["unreliable"],
        "leg_model": scenario.leg_model,
        "cruise_airspeed": scenario.cruise_airspeed,
        "error_unit": scenario.error_unit,
        "capture_radius": scenario.capture_radius,
    }
    row.update({k: float(getattr(scenario.params, k)) for k in PARAMETER_FIELDS})
    return row


def _describe(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".rstrip(": ")


def finish_row(row: dict, started: float) -> dict:
    row["cell_seconds"] = time.perf_counter() - started
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    row["finished_at"] = datetime.now(timezone.utc).isoformat(timespec="seconds")
    return row
