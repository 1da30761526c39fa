"""The cost of wind: both workbooks, Table 2's limits, each autopilot's shipped defaults
(``--firmware``), design winds of 0, 5 and 10 m/s, planned through the installed command line as
a user would (``gcs-planner plan ... --json``), with the straight run-in and run-out at every
landmark that the envelope derives (docs/model.md, "Straight at every landmark") and, for
comparison, without them (``--approach 0 --departure 0``).

Each row: the derived envelope (TAS at the highest point, R, climb/descent angles, runs), the
front's size and proof, and the chosen route (default rule: at least 0.99 likely to arrive, else
the most reliable). Planning time is that of the whole process (numba's cache warm after the
first row).

A wind may carry the direction it blows from (``--winds 10,10@90``): the plan holds each leg's
climb and descent along its own track in that wind (docs/model.md, "Flight in the real world").

    python -m benchmarks.wind [--winds 0,5,10] [--firmwares ardupilot,px4] [--no-runs-column]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from benchmarks.cases import DATA
from benchmarks.report import table

# The paper's Table 2 (docs/model.md): the limits the workbooks are planned with.
TABLE2 = {
    "dataset1": ("25", "15", "20", "25", "30", "0.001"),
    "dataset2": ("20", "10", "15", "20", "20", "0.001"),
}
FLAGS = ("--alpha1", "--alpha2", "--beta1", "--beta2", "--theta", "--delta")
NAMES = {"ardupilot": "ArduPlane", "px4": "PX4"}


@dataclass
class WindRow:
    workbook: str
    firmware: str
    wind: str  # SPEED[@FROM_DEG], as given to --wind
    tas: float
    radius: float
    climb: float
    descent: float
    # planned with --per-leg-envelope: (R at the lowest point, length, corrections, P), or
    # (R, None, None, None) with no route
    per_leg: tuple[float, float | None, int | None, float | None] | None
    runs: float  # derived run-in = run-out, m
    front: int
    proven: bool
    length: float | None
    corrections: int | None
    probability: float | None
    # the route chosen when planned with --approach 0 --departure 0: (length, corrections, P)
    without_runs: tuple[float, int, float] | None
    seconds: float


def wind_label(wind: str) -> str:
    """``10@90`` as "10 m/s from 90°"; ``0`` as "0 m/s"."""
    speed, _, towards = wind.partition("@")
    return f"{float(speed):g} m/s" + (f" from {float(towards):g}°" if towards else "")


def _plan(workbook: str, firmware: str, wind: str, extra: tuple[str, ...] = ()) -> dict:
    path = Path(DATA) / f"{workbook}.xlsx"
    args = [str(path)]
    for flag, value in zip(FLAGS, TABLE2[workbook]):
        args += [flag, value]
    args += ["--firmware", firmware, "--wind", wind, "--json", "--quiet", *extra]
    exe = Path(sys.executable).with_name("gcs-planner")
    out = subprocess.run(
        [str(exe), "plan", *args], capture_output=True, text=True, check=False, timeout=900
    )
    if out.returncode not in (0, 3):
        raise RuntimeError(
            f"gcs-planner plan {' '.join(args)}: exit {out.returncode}\n{out.stderr}"
        )
    if not out.stdout.strip():  # infeasible (exit 3): the reason is on stderr
        return {"infeasible": out.stderr.strip().splitlines()[-1] if out.stderr else "?"}
    return json.loads(out.stdout)


def _envelope(workbook: str, firmware: str, wind: str) -> dict:
    """The derived envelope of an infeasible case (no plan JSON to read it from), derived as the
    command line derives it (``cli.vehicle_from.derive_envelope``)."""
    from gcs_planner.aircraft.derive import derive_envelope
    from gcs_planner.cli import build_parser
    from gcs_planner.cli.common import load_scenario_from_args

    argv = ["plan", str(Path(DATA) / f"{workbook}.xlsx")]
    for flag, value in zip(FLAGS, TABLE2[workbook]):
        argv += [flag, value]
    argv += ["--firmware", firmware, "--wind", wind]
    args = build_parser(argv).parse_args(argv)
    scenario = derive_envelope(args, load_scenario_from_args(args), wind_text=args.wind)
    assert scenario.envelope is not None
    return scenario.envelope.to_dict()


def _chosen(plan: dict) -> dict | None:
    k = plan.get("chosen")
    if "front" not in plan:
        return None
    return None if k is None else plan["front"][k]


def run_wind(
    winds: tuple[str, ...], firmwares: tuple[str, ...], compare: bool = True
) -> list[WindRow]:
    rows = []
    for workbook in ("dataset1", "dataset2"):
        for firmware in firmwares:
            for wind in winds:
                t0 = time.perf_counter()
                plan = _plan(workbook, firmware, wind)
                seconds = time.perf_counter() - t0
                if "infeasible" in plan:
                    print(f"{workbook} {firmware} {wind_label(wind)}: {plan['infeasible']}")
                    plan = {"vehicle": {"envelope": None}, "front": [], "chosen": None,
                            "optimality": {"optimal": True}}  # fmt: skip
                env = plan["vehicle"]["envelope"] or _envelope(workbook, firmware, wind)
                chosen = _chosen(plan)
                plain = None
                if compare:
                    other = _chosen(
                        _plan(workbook, firmware, wind, ("--approach", "0", "--departure", "0"))
                    )
                    if other is not None:
                        plain = (other["length"], other["corrections"], other["probability"])
                per_leg = None
                if compare:
                    leg_plan = _plan(workbook, firmware, wind, ("--per-leg-envelope",))
                    each = _chosen(leg_plan)
                    low_r = env["low_turn_radius"]
                    per_leg = (
                        (low_r, None, None, None)
                        if each is None
                        else (low_r, each["length"], each["corrections"], each["probability"])
                    )
                rows.append(
                    WindRow(
                        workbook=workbook,
                        firmware=firmware,
                        wind=wind,
                        tas=env["tas"],
                        radius=env["turn_radius"],
                        climb=env["max_climb_angle"],
                        descent=env["max_descent_angle"],
                        per_leg=per_leg,
                        runs=env["approach_m"],
                        front=len(plan["front"]),
                        proven=bool(plan["optimality"]["optimal"]),
                        length=None if chosen is None else chosen["length"],
                        corrections=None if chosen is None else chosen["corrections"],
                        probability=None if chosen is None else chosen["probability"],
                        without_runs=plain,
                        seconds=seconds,
                    )
                )
    return rows


def wind_table(rows: list[WindRow]) -> str:
    header = [
        "workbook", "autopilot", "wind", "TAS", "R", "climb / descent", "run-in = run-out",
        "front", "proven", "chosen: length", "corrections", "P",
        "without the runs: length, corrections, P",
        "--per-leg-envelope: R at the lowest point; length, corrections, P",
    ]  # fmt: skip
    body = []
    for r in rows:
        body.append(
            [
                r.workbook.replace("dataset", "dataset "),
                NAMES.get(r.firmware, r.firmware),
                wind_label(r.wind),
                f"{r.tas:.1f} m/s",
                f"{r.radius:.0f} m",
                f"{r.climb:.1f}° / {r.descent:.1f}°",
                f"{r.runs:.0f} m",
                r.front if r.front else "none: infeasible",
                "yes" if r.proven else "no",
                "–" if r.length is None else f"{r.length:,.1f} m",
                "–" if r.corrections is None else r.corrections,
                "–" if r.probability is None else f"{r.probability:.3f}",
                "–" if r.without_runs is None else "{:,.1f} m, {}, {:.3f}".format(*r.without_runs),
                _per_leg_cell(r.per_leg),
            ]
        )
    return table(header, body)


def _per_leg_cell(per_leg: tuple | None) -> str:
    if per_leg is None:
        return "–"
    low, length, corrections, p = per_leg
    if length is None:
        return f"{low:.0f} m; no route"
    return f"{low:.0f} m; {length:,.1f} m, {corrections}, {p:.3f}"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.wind", description=__doc__)
    parser.add_argument("--winds", default="0,5,10")
    parser.add_argument("--firmwares", default="ardupilot,px4")
    parser.add_argument("--no-runs-column", action="store_true",
                        help="skip the comparison plans without the runs")  # fmt: skip
    args = parser.parse_args(argv)
    winds = tuple(w.strip() for w in args.winds.split(","))
    firmwares = tuple(args.firmwares.split(","))
    rows = run_wind(winds, firmwares, compare=not args.no_runs_column)
    print(wind_table(rows))


if __name__ == "__main__":
    main()
