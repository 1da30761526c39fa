"""Sweeps on Dask against a serial loop: the same cells, the same task function.

    python -m benchmarks.sweep                  # the bundled example, then 200 contest-like
                                                # scenarios of 613 points
    python -m benchmarks.sweep --scenarios 20   # a shorter run

0. the bundled example (``missions/sweep-example.toml``: 24 cells, each chosen route dry-run 50
   times): the loop over its cells in this process, then ``gcs-planner sweep``'s own local
   cluster started, run and stopped, as the command does (start and stop timed and included);

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
gain least when fewer than two cores are free. Besides the planning processes' CPU seconds the
table gives those of the processes that only coordinate (this process as client, scheduler and
nannies for the local cluster; the client, `dask scheduler` and `dask worker`'s nanny process
for the separate one): on two cores every one of them is taken from the workers.
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
from datetime import datetime, timezone
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
    start_stop: float = 0.0  # of ``seconds``: starting and stopping the cluster
    coordinating_cpu: float = 0.0  # CPU s of the client, scheduler and nannies


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


def _on_cluster(
    spec_path: Path, out: Path, client, address: str, others: tuple = ()
) -> tuple[float, float, float, dict]:
    """Wall time, the workers' CPU s, the coordinating processes' CPU s (this one and
    ``others``, psutil processes) and the fronts of one sweep on the cluster at ``address``."""
    cpu = _worker_cpu(client)
    mine, theirs = time.process_time(), _cpu_of(others)
    start = time.perf_counter()
    run_sweep(spec_path, out, scheduler=address)
    seconds = time.perf_counter() - start
    coordinating = time.process_time() - mine + _cpu_of(others) - theirs
    return seconds, _worker_cpu(client) - cpu, coordinating, _fronts(out)


def _cpu_of(processes: tuple) -> float:
    return sum(sum(p.cpu_times()[:2]) for p in processes)


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
    local = [0.0, 0.0, 0.0]
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
            c_wall, c_cpu, c_coord, c_fronts = _on_cluster(
                spec_path, folder / f"local{r}", client, address
            )
            if c_fronts != s_fronts:
                raise RuntimeError(f"round {r}: the sweep's fronts differ from the serial loop's")
            fronts.update(s_fronts)
            serial = [serial[0] + s_wall, serial[1] + s_cpu]
            local = [local[0] + c_wall, local[1] + c_cpu, local[2] + c_coord]
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
            f"local cluster, {workers} workers × 1 thread (incl. start + stop)",
            local[0] + startup,
            local[1],
            scenarios,
            load,
            start_stop=startup,
            coordinating_cpu=local[2],
        ),
    ]
    return timings, ratios, fronts


EXAMPLE_SPEC = Path(__file__).resolve().parents[1] / "missions" / "sweep-example.toml"


def run_example(
    folder: Path, workers: int = 2, spec_path: Path = EXAMPLE_SPEC
) -> tuple[list[Timing], dict]:
    """The bundled example: the serial loop, then the local cluster `gcs-planner sweep`
    starts (its start and stop timed), the fronts checked equal."""
    from gcs_planner.sweep.runner import _connect, _disconnect

    before = _load()
    s_wall, s_cpu, s_fronts = _serial(spec_path)
    start = time.perf_counter()
    client, cluster = _connect(None, workers, 1, "127.0.0.1:0")
    try:
        client.wait_for_workers(workers, timeout=DEADLINE_S)
        startup = time.perf_counter() - start
        c_wall, c_cpu, c_coord, c_fronts = _on_cluster(
            spec_path, folder / "example", client, cluster.scheduler_address
        )
    finally:
        stop = time.perf_counter()
        _disconnect(client, cluster)
        startup += time.perf_counter() - stop
    if c_fronts != s_fronts:
        raise RuntimeError("the example's fronts on the cluster differ from the serial loop's")
    after = _load()
    load = (min(before, after), max(before, after))
    cells = len(s_fronts)
    name = f"local cluster, {workers} workers × 1 thread (incl. start + stop)"
    timings = [
        Timing("serial loop (1 process)", s_wall, s_cpu, cells, load),
        Timing(name, c_wall + startup, c_cpu, cells, load, startup, c_coord),
    ]
    print(
        f"  example: serial {s_wall:.1f} s, cluster {c_wall + startup:.1f} s "
        f"({s_wall / (c_wall + startup):.2f}x)",
        flush=True,
    )
    return timings, s_fronts


def _timing_table(timings: list[Timing], serial: Timing) -> list[str]:
    """The rows of a timing table (header first), each run against the serial loop."""
    lines = [
        "| run | cells | wall time s | of which start + stop s | speed-up vs serial "
        "| without start + stop | planning CPU s | coordinating CPU s | load avg (1 min) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for t in timings:
        work = t.seconds - t.start_stop
        lines.append(
            f"| {t.name} | {t.cells} | {t.seconds:,.1f} | {t.start_stop:.1f} | "
            f"{serial.seconds / t.seconds:.2f}× | {serial.seconds / work:.2f}× | "
            f"{t.cpu_seconds:,.1f} | {t.coordinating_cpu:.1f} | "
            f"{t.load[0]:.1f}–{t.load[1]:.1f} |"
        )
    return lines


def render_example(timings: list[Timing], spec_path: Path = EXAMPLE_SPEC) -> str:
    """The example's table: serial loop against the local cluster, the same columns."""
    serial = timings[0]
    lines = [
        f"`{spec_path.name}`: {serial.cells} cells, each chosen route dry-run; identical "
        "fronts from both runs.",
        "",
        *_timing_table(timings, serial),
    ]
    return "\n".join(lines)


def run_separate(spec_path: Path, out: Path, workers: int) -> tuple[Timing, dict]:
    """A scheduler and workers started as their own processes with the `dask` command."""
    import psutil
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
                others = tuple(psutil.Process(p.pid) for p in procs)  # scheduler, nannies
                seconds, cpu, coordinating, fronts = _on_cluster(
                    spec_path, out, client, address, others
                )
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
    load = (min(before, after), max(before, after))
    return Timing(name, seconds, cpu, cells, load, coordinating_cpu=coordinating), fronts


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
    print(f"  started {_utc()}", flush=True)
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
    print(f"  ended {_utc()}", flush=True)
    return timings, ratios


def _utc() -> str:
    return datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")


def render(
    timings: list[Timing],
    ratios: list[float],
    scenarios: int,
    corrections: int,
    radius: float,
    when: str = "",
) -> str:
    serial = timings[0]
    lines = [
        (f"Measured {when}. " if when else "")
        + f"{scenarios} scenarios `random_scenario({corrections}, seed)` "
        f"({corrections + 2} points), turning radius {radius:g} m, the default objectives; "
        "identical fronts from every run. Serial and local cluster alternate in "
        f"{len(ratios)} rounds of seeds (per-round speed-up "
        f"{min(ratios):.2f}–{max(ratios):.2f}×, median {statistics.median(ratios):.2f}×); "
        "the separate scheduler runs all cells at once after them (its processes' start and "
        "stop not timed). Planning CPU s: of the process(es) that planned — this one for the "
        "loop, the workers for a cluster; coordinating CPU s: of the client, the scheduler and "
        "the nannies.",
        "",
        *_timing_table(timings, serial),
    ]
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
    ap.add_argument("--no-example", action="store_true", help="skip the bundled example")
    ap.add_argument(
        "--rounds", type=int, default=8, help="alternating rounds of serial and local cluster"
    )
    args = ap.parse_args(argv)
    if min(args.scenarios, args.corrections, args.workers, args.rounds) < 1 or args.turn_radius < 0:
        ap.error("--scenarios, --corrections and --workers must be >= 1, --turn-radius >= 0")
    started = _utc()
    example = None
    if not args.no_example:
        with tempfile.TemporaryDirectory() as tmp:
            example, _ = run_example(Path(tmp), args.workers)
    timings, ratios = run_benchmark(
        args.scenarios,
        args.corrections,
        args.workers,
        args.turn_radius,
        not args.no_separate,
        args.rounds,
    )
    when = (
        f"{started} – {_utc()[-9:]}, `python -m benchmarks.sweep {' '.join(argv or sys.argv[1:])}`"
    )
    if example is not None:
        print(render_example(example) + "\n")
    print(render(timings, ratios, args.scenarios, args.corrections, args.turn_radius, when))


if __name__ == "__main__":
    main()
