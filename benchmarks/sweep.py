"""Sweeps on Dask against a serial loop: the same cells, the same task function.

    python -m benchmarks.sweep                  # 200 contest-like scenarios of 613 points
    python -m benchmarks.sweep --scenarios 20   # a shorter run

The cells are ``random_scenario(611, seed)`` for seeds 1..N (A, 611 correction points and B: the
contest's 613 points in its 100 km box, dataset 1's parameters, 24 % of the points unreliable),
planned in the planner's default mode: turning radius 200 m and the objectives `gcs-planner
plan` uses by default (length, corrections, and probability since there are unreliable points).

1. serial: ``run_cell`` on each cell in a loop in this process;
2. local cluster: ``run_sweep`` with the LocalCluster it starts itself (``--workers`` processes,
   one thread each), cluster start and stop included;
3. separate scheduler: ``dask scheduler`` and ``dask worker --nworkers W --nthreads 1`` started
   as their own processes (as a user with a cluster would), then ``run_sweep(scheduler=...)``;
   the processes' start is not timed.

Each run writes its results into a fresh folder; the fronts of the three are checked equal, so
the ratio compares equal work. The load average before and after each run is reported: on a
shared machine other users' processes take cores from whichever run is going, and two workers
gain least when fewer than two cores are free.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from gcs_planner.sweep import expand, read_results, read_spec, run_cell, run_sweep

CORRECTIONS = 611  # + A + B = the contest's 613 points
DEADLINE_S = 120.0


@dataclass(frozen=True)
class Timing:
    name: str
    seconds: float
    cells: int
    load_before: float
    load_after: float


def spec_text(scenarios: int, corrections: int, turn_radius: float) -> str:
    return f"""name = "benchmark-{scenarios}x{corrections + 2}"

[[scenarios]]
generate = "random"
corrections = {corrections}
seeds = {{ first = 1, count = {scenarios} }}
parameters = "dataset1"

[grid]
turn_radius = {turn_radius:g}
"""


def _load() -> float:
    return os.getloadavg()[0]


def run_serial(spec_path: Path) -> tuple[Timing, dict]:
    cells = expand(read_spec(spec_path))
    before, start = _load(), time.perf_counter()
    fronts = {}
    for cell in cells:
        rows = run_cell(cell)
        fronts[cell.key] = _front(rows)
    seconds = time.perf_counter() - start
    return Timing("serial loop (1 process)", seconds, len(cells), before, _load()), fronts


def run_local(spec_path: Path, out: Path, workers: int) -> tuple[Timing, dict]:
    before, start = _load(), time.perf_counter()
    result = run_sweep(spec_path, out, workers=workers)
    seconds = time.perf_counter() - start
    name = f"local cluster, {workers} workers x 1 thread (start and stop included)"
    return Timing(name, seconds, result.ran, before, _load()), _fronts(out)


def run_separate(spec_path: Path, out: Path, workers: int) -> tuple[Timing, dict]:
    """A scheduler and workers started as their own processes with the `dask` command."""
    from distributed import Client

    dask = str(Path(sys.executable).parent / "dask")
    with tempfile.TemporaryDirectory() as tmp:
        scheduler_file = Path(tmp) / "scheduler.json"
        procs = [
            subprocess.Popen(
                [dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                 "--scheduler-file", str(scheduler_file)],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            )
        ]  # fmt: skip
        try:
            _wait(lambda: scheduler_file.exists() and "address" in scheduler_file.read_text())
            address = json.loads(scheduler_file.read_text())["address"]
            procs.append(
                subprocess.Popen(
                    [dask, "worker", address, "--nworkers", str(workers), "--nthreads", "1",
                     "--host", "127.0.0.1", "--no-dashboard"],
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                )
            )  # fmt: skip
            with Client(address) as client:
                client.wait_for_workers(workers, timeout=DEADLINE_S)
            before, start = _load(), time.perf_counter()
            result = run_sweep(spec_path, out, scheduler=address)
            seconds = time.perf_counter() - start
        finally:
            for p in reversed(procs):
                p.terminate()
            for p in reversed(procs):
                try:
                    p.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    p.kill()
    name = f"`dask scheduler` + `dask worker --nworkers {workers} --nthreads 1`"
    return Timing(name, seconds, result.ran, before, _load()), _fronts(out)


def _wait(condition) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not condition():
        if time.monotonic() > deadline:
            raise RuntimeError("the dask scheduler did not write its address")
        time.sleep(0.05)


def _front(rows: list[dict]) -> tuple:
    """A cell's answer: its status and front (route ids and lengths), to compare runs."""
    return tuple(
        (
            r["status"],
            r.get("route_ids"),
            None if r.get("length") is None else round(r["length"], 6),
        )
        for r in sorted(rows, key=_route)
    )


def _route(row: dict) -> int:
    return row["route"] if row.get("route") is not None else -1


def _fronts(out: Path) -> dict:
    cells: dict[str, list[dict]] = {}
    for row in read_results(out):
        cells.setdefault(row["cell_key"], []).append(row)
    return {key: _front(rows) for key, rows in cells.items()}


def run_benchmark(
    scenarios: int,
    corrections: int = CORRECTIONS,
    workers: int = 2,
    turn_radius: float = 200.0,
    separate: bool = True,
) -> list[Timing]:
    with tempfile.TemporaryDirectory() as tmp:
        spec_path = Path(tmp) / "spec.toml"
        spec_path.write_text(spec_text(scenarios, corrections, turn_radius), encoding="utf-8")
        timings, fronts = [], []
        for step in ("serial", "local", "separate"):
            if step == "serial":
                t, f = run_serial(spec_path)
            elif step == "local":
                t, f = run_local(spec_path, Path(tmp) / "local", workers)
            elif separate:
                t, f = run_separate(spec_path, Path(tmp) / "separate", workers)
            else:
                continue
            print(f"  {t.name}: {t.seconds:.1f} s", flush=True)
            timings.append(t)
            fronts.append(f)
        if any(f != fronts[0] for f in fronts[1:]):
            raise RuntimeError("the sweep's fronts differ from the serial loop's")
    return timings


def render(timings: list[Timing], scenarios: int, corrections: int, turn_radius: float) -> str:
    serial = timings[0].seconds
    lines = [
        f"{scenarios} scenarios `random_scenario({corrections}, seed)` "
        f"({corrections + 2} points), turning radius {turn_radius:g} m, the default "
        "objectives; identical fronts from every run.",
        "",
        "| run | cells | wall time s | speed-up vs serial | load avg before → after |",
        "|---|---:|---:|---:|---|",
    ]
    for t in timings:
        lines.append(
            f"| {t.name} | {t.cells} | {t.seconds:,.1f} | {serial / t.seconds:.2f}× | "
            f"{t.load_before:.1f} → {t.load_after:.1f} |"
        )
    lines.append("")
    lines.append(f"CPUs seen by this process: {os.cpu_count()}.")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.sweep", description=__doc__)
    ap.add_argument("--scenarios", type=int, default=200)
    ap.add_argument("--corrections", type=int, default=CORRECTIONS)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument(
        "--turn-radius", type=float, default=200.0, help="0: straight legs (the fast mode)"
    )
    ap.add_argument("--no-separate", action="store_true", help="skip the separate scheduler")
    args = ap.parse_args(argv)
    if min(args.scenarios, args.corrections, args.workers) < 1 or args.turn_radius < 0:
        ap.error("--scenarios, --corrections and --workers must be >= 1, --turn-radius >= 0")
    timings = run_benchmark(
        args.scenarios, args.corrections, args.workers, args.turn_radius, not args.no_separate
    )
    print(render(timings, args.scenarios, args.corrections, args.turn_radius))


if __name__ == "__main__":
    main()
