"""Sweeps on Dask against a serial loop: the same cells, the same task function.

    python -m benchmarks.sweep                  # 200 contest-like scenarios of 613 points
    python -m benchmarks.sweep --scenarios 20   # a shorter run

The cells are ``random_scenario(611, seed)`` for seeds 1..N (A, 611 correction points and B: the
contest's 613 points in its 100 km box, dataset 1's parameters, 24 % of the points unreliable),
planned in the planner's default mode: turning radius 200 m and the objectives `gcs-planner
plan` uses by default (length, corrections, and probability since there are unreliable points).

1. serial: ``run_cell`` on each cell in a loop in this process;
2. local cluster: the LocalCluster `gcs-planner sweep` starts (``--workers`` processes, one
   thread each) and ``run_sweep`` on it; its start and stop are timed and added. The two
   alternate in ``--rounds`` rounds over blocks of seeds, so that a drifting load weighs on both;
3. separate scheduler: ``dask scheduler`` and ``dask worker --nworkers W --nthreads 1`` started
   as their own processes (as a user with a cluster would), then ``run_sweep(scheduler=...)``
   over all cells; the processes' start is not timed.

Each run writes its results into a fresh folder; the fronts of the three are checked equal, so
the ratio compares equal work. The load average before and after each run is reported: on a
shared machine other users' processes take cores from whichever run is going, and two workers
gain least when fewer than two cores are free.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
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
    seconds: float  # wall time
    cpu_seconds: float  # of the process(es) that planned: this one, or the workers
    cells: int
    load: tuple[float, float]  # lowest and highest 1-minute load average seen around the run


def spec_text(scenarios: int, corrections: int, turn_radius: float, first: int = 1) -> str:
    return f"""name = "benchmark-{scenarios}x{corrections + 2}"

[[scenarios]]
generate = "random"
corrections = {corrections}
seeds = {{ first = {first}, count = {scenarios} }}
parameters = "dataset1"

[grid]
turn_radius = {turn_radius:g}
"""


def _load() -> float:
    return os.getloadavg()[0]


def _worker_cpu(client) -> float:
    return sum(client.run(time.process_time).values())


def _serial(spec_path: Path) -> tuple[float, float, dict]:
    cells = expand(read_spec(spec_path))
    start, cpu = time.perf_counter(), time.process_time()
    fronts = {cell.key: _front(run_cell(cell)) for cell in cells}
    return time.perf_counter() - start, time.process_time() - cpu, fronts


def _on_cluster(spec_path: Path, out: Path, client, address: str) -> tuple[float, float, dict]:
    cpu = _worker_cpu(client)
    start = time.perf_counter()
    run_sweep(spec_path, out, scheduler=address)
    seconds = time.perf_counter() - start
    return seconds, _worker_cpu(client) - cpu, _fronts(out)


def run_interleaved(
    folder: Path, scenarios: int, corrections: int, workers: int, turn_radius: float, rounds: int
) -> tuple[list[Timing], list[float], dict]:
    """Serial and local cluster in alternating rounds over blocks of seeds, so that a shared
    machine's load, which drifts over minutes, weighs on both alike. The cluster is the one
    `gcs-planner sweep` starts (runner's LocalCluster); its start and stop are timed once and
    added to its total."""
    from gcs_planner.sweep.runner import _connect

    loads = [_load()]
    start = time.perf_counter()
    client, cluster = _connect(None, workers, 1, "127.0.0.1:0")
    client.wait_for_workers(workers, timeout=DEADLINE_S)
    startup = time.perf_counter() - start
    serial = [0.0, 0.0]
    local = [0.0, 0.0]
    ratios: list[float] = []
    fronts: dict = {}
    try:
        size = -(-scenarios // rounds)
        for r, first in enumerate(range(1, scenarios + 1, size)):
            count = min(size, scenarios + 1 - first)
            spec_path = folder / f"round{r}.toml"
            spec_path.write_text(spec_text(count, corrections, turn_radius, first), "utf-8")
            s_wall, s_cpu, s_fronts = _serial(spec_path)
            address = cluster.scheduler_address
            c_wall, c_cpu, c_fronts = _on_cluster(spec_path, folder / f"local{r}", client, address)
            if c_fronts != s_fronts:
                raise RuntimeError(f"round {r}: the sweep's fronts differ from the serial loop's")
            fronts.update(s_fronts)
            serial = [serial[0] + s_wall, serial[1] + s_cpu]
            local = [local[0] + c_wall, local[1] + c_cpu]
            ratios.append(s_wall / c_wall)
            loads.append(_load())
            print(
                f"  round {r + 1}: {count} cells, serial {s_wall:.1f} s, cluster {c_wall:.1f} s "
                f"({s_wall / c_wall:.2f}x), load {loads[-1]:.1f}",
                flush=True,
            )
    finally:
        start = time.perf_counter()
        client.close()
        cluster.close()
        startup += time.perf_counter() - start
    load = (min(loads), max(loads))
    timings = [
        Timing("serial loop (1 process)", serial[0], serial[1], scenarios, load),
        Timing(
            f"local cluster, {workers} workers × 1 thread (incl. {startup:.1f} s start + stop)",
            local[0] + startup,
            local[1],
            scenarios,
            load,
        ),
    ]
    return timings, ratios, fronts


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
                before = _load()
                seconds, cpu, fronts = _on_cluster(spec_path, out, client, address)
            after = _load()
        finally:
            for p in reversed(procs):
                p.terminate()
            for p in reversed(procs):
                try:
                    p.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    p.kill()
    name = f"`dask scheduler` + `dask worker --nworkers {workers} --nthreads 1`"
    cells = len(fronts)
    return Timing(name, seconds, cpu, cells, (min(before, after), max(before, after))), fronts


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
    rounds: int = 8,
) -> tuple[list[Timing], list[float]]:
    """The timings (serial, local cluster[, separate scheduler]) and the per-round ratios."""
    rounds = max(1, min(rounds, scenarios))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        timings, ratios, fronts = run_interleaved(
            folder, scenarios, corrections, workers, turn_radius, rounds
        )
        for t in timings:
            print(f"  {t.name}: {t.seconds:.1f} s", flush=True)
        if separate:
            spec_path = folder / "all.toml"
            spec_path.write_text(spec_text(scenarios, corrections, turn_radius), "utf-8")
            t, f = run_separate(spec_path, folder / "separate", workers)
            if f != fronts:
                raise RuntimeError("the separate cluster's fronts differ from the serial loop's")
            print(f"  {t.name}: {t.seconds:.1f} s", flush=True)
            timings.append(t)
    return timings, ratios


def render(
    timings: list[Timing], ratios: list[float], scenarios: int, corrections: int, radius: float
) -> str:
    serial = timings[0]
    lines = [
        f"{scenarios} scenarios `random_scenario({corrections}, seed)` "
        f"({corrections + 2} points), turning radius {radius:g} m, the default objectives; "
        "identical fronts from every run. Serial and local cluster alternate in "
        f"{len(ratios)} rounds of seeds (per-round speed-up "
        f"{min(ratios):.2f}–{max(ratios):.2f}×, median {statistics.median(ratios):.2f}×); "
        "the separate scheduler runs all cells at once after them. CPU s: of the planning "
        "process(es) — this one for the loop, the workers for a cluster.",
        "",
        "| run | cells | wall time s | speed-up vs serial | CPU s | load avg (1 min) |",
        "|---|---:|---:|---:|---:|---|",
    ]
    for t in timings:
        lines.append(
            f"| {t.name} | {t.cells} | {t.seconds:,.1f} | {serial.seconds / t.seconds:.2f}× | "
            f"{t.cpu_seconds:,.1f} | {t.load[0]:.1f}–{t.load[1]:.1f} |"
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
    ap.add_argument(
        "--rounds", type=int, default=8, help="alternating rounds of serial and local cluster"
    )
    args = ap.parse_args(argv)
    if min(args.scenarios, args.corrections, args.workers, args.rounds) < 1 or args.turn_radius < 0:
        ap.error("--scenarios, --corrections and --workers must be >= 1, --turn-radius >= 0")
    timings, ratios = run_benchmark(
        args.scenarios,
        args.corrections,
        args.workers,
        args.turn_radius,
        not args.no_separate,
        args.rounds,
    )
    print(render(timings, ratios, args.scenarios, args.corrections, args.turn_radius))


if __name__ == "__main__":
    main()
