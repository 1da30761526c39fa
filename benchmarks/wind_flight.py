"""Plans for the autopilot in the wind it flies, flown: both workbooks with Table 2's limits,
each autopilot's shipped envelope (``--firmware``), design winds 0, 5 and 10 m/s, each plan
dry-run on the mock vehicle set up for it (``--set-params``) in a wind of the design speed from
a direction drawn per run (``--wind W --runs N``), through the installed command line as a
user would. The route flown is the default choice (at least 0.99 likely to arrive, else the
most reliable) and, with ``--most-reliable``, also the most reliable route of the front.

Each cell: planned length and probability, then the success rate with its 99 % Wilson interval
and the runs lost by the flight (a missed landmark, or lost where the plan flown with the same
correction outcomes arrives) and by failed corrections.

A wind with a direction (``--winds 10@90``) is the plan's design wind and the wind every run
flies: the plan holds each leg along its own track in that wind only.

    python -m benchmarks.wind_flight [--runs 200] [--winds 0,5,10] [--most-reliable]
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
from benchmarks.wind import FLAGS, NAMES, TABLE2, wind_label
from gcs_planner.aircraft.autopilot import effective


@dataclass
class FlightCell:
    workbook: str
    firmware: str
    wind: str  # SPEED[@FROM_DEG], as given to --wind
    choice: str
    planned_length: float | None  # None: no route (exit 3)
    planned_probability: float | None
    success_rate: float | None
    ci: tuple[float, float] | None
    flight_losses: int
    correction_losses: int
    seconds: float


def fly(
    workbook: str, firmware: str, wind: str, runs: int, choice: str, extra: tuple[str, ...] = ()
) -> FlightCell:
    args = [str(Path(DATA) / f"{workbook}.xlsx")]
    for flag, value in zip(FLAGS, TABLE2[workbook]):
        args += [flag, value]
    # dry-run's --firmware names the flown autopilot only (it does not change the plan): the
    # shipped envelope is stated, as a user planning for that autopilot would
    shipped = effective(firmware, {})
    args += ["--firmware", firmware, "--cruise-airspeed", f"{shipped.cruise_airspeed:g}",
             "--max-bank-angle", f"{shipped.bank_limit:g}", "--max-climb-rate",
             f"{shipped.climb_rate:g}", "--max-sink-rate", f"{shipped.sink_rate:g}",
             "--wind", wind, "--runs", str(runs), "--set-params", "--json",
             "--quiet"]  # fmt: skip
    if choice != "default":
        args += ["--choose", choice]
    args += list(extra)
    exe = Path(sys.executable).with_name("gcs-planner")
    t0 = time.perf_counter()
    out = subprocess.run(
        [str(exe), "dry-run", *args], capture_output=True, text=True, check=False, timeout=1800
    )
    seconds = time.perf_counter() - t0
    if out.returncode == 3:  # no route
        return FlightCell(workbook, firmware, wind, choice, None, None, None, None, 0, 0, seconds)
    if not out.stdout.strip():
        raise RuntimeError(f"gcs-planner dry-run {' '.join(args)}: exit {out.returncode}\n"
                           f"{out.stderr}")  # fmt: skip
    d = json.loads(out.stdout)
    return FlightCell(
        workbook, firmware, wind, choice, d["planned_length"], d["planned_probability"],
        d["success_rate"], tuple(d["success_ci"]), d["flight_losses"], d["correction_losses"],
        seconds,
    )  # fmt: skip


def _cell(c: FlightCell) -> str:
    if c.planned_length is None:
        return "no route (exit 3)"
    lo, hi = c.ci
    return (
        f"{c.planned_length / 1000:.1f} km, P {c.planned_probability:.2f}: {c.success_rate:.2f} "
        f"[{lo:.2f}–{hi:.2f}] ({c.flight_losses} / {c.correction_losses})"
    )


def render(cells: list[FlightCell], winds: tuple[str, ...]) -> str:
    head = "| case | " + " | ".join(f"wind {wind_label(w)}" for w in winds) + " |"
    lines = [head, "|---" * (len(winds) + 1) + "|"]
    keys = sorted({(c.workbook, c.firmware, c.choice) for c in cells},
                  key=lambda k: (k[0], k[1] != "ardupilot", k[2]))  # fmt: skip
    for wb, fw, choice in keys:
        row = {c.wind: c for c in cells if (c.workbook, c.firmware, c.choice) == (wb, fw, choice)}
        name = f"dataset {wb[-1]}, {NAMES[fw]}" + ("" if choice == "default" else f", {choice}")
        lines.append(f"| {name} | " + " | ".join(_cell(row[w]) for w in winds) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.wind_flight", description=__doc__)
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--winds", default="0,5,10")
    parser.add_argument("--firmwares", default="ardupilot,px4")
    parser.add_argument("--most-reliable", action="store_true",
                        help="also fly the front's most reliable route")  # fmt: skip
    parser.add_argument("--per-leg-envelope", action="store_true",
                        help="plan each leg on its own envelope")  # fmt: skip
    a = parser.parse_args(argv)
    extra = ("--per-leg-envelope",) if a.per_leg_envelope else ()
    winds = tuple(w.strip() for w in a.winds.split(","))
    choices = ("default", "most-reliable") if a.most_reliable else ("default",)
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    cells = []
    for workbook in ("dataset1", "dataset2"):
        for firmware in a.firmwares.split(","):
            for choice in choices:
                for wind in winds:
                    c = fly(workbook, firmware, wind, a.runs, choice, extra)
                    cells.append(c)
                    print(f"  {workbook} {firmware} {choice} {wind_label(wind)}: {_cell(c)} "
                          f"in {c.seconds:.0f} s", flush=True)  # fmt: skip
    print(f"\nMeasured {started}, `python -m benchmarks.wind_flight --runs {a.runs}"
          f"{'' if a.winds == '0,5,10' else ' --winds ' + a.winds}"
          f"{' --most-reliable' if a.most_reliable else ''}"
          f"{' '.join(('', *extra))}`:\n")  # fmt: skip
    print(render(cells, winds))


if __name__ == "__main__":
    main()
