"""Section 6: how long a user waits for the command line, as whole processes, beside the floor
of any numpy/scipy program on the same machine in the same run.

Each command is a fresh ``python -m gcs_planner ...`` process (what the installed ``gcs-planner``
script runs); the runs of the commands are interleaved so that a change in the machine's load
falls on all of them alike. The planner's own search time comes from the plan JSON's ``stats``,
so the start-up overhead is what is left: total − floor − search. The CPU time (user + system)
of each process is reported beside its wall time: on a shared machine it is the steadier
measure.

    python -m benchmarks --startup            # this section alone
    python -m benchmarks.startup              # the same, as a script

The first row after the floor is issue 54's figure: dataset 2's default plan (the paper's Table 2
flags; turns R 200 m, three objectives), CPU of the whole process, median of 5, against the
floor measured in the same rounds. It is measured as a user who never ran ``gcs-planner
compile`` sees it: numba's cache an empty folder of its own (``NUMBA_CACHE_DIR``), one first
plan (which starts the background compile, gcs_planner/runtime/background_compile.py), then the
rounds once that compile has ended (the benchmark waits on its lock file).
"""

from __future__ import annotations

import compileall
import fcntl
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import gcs_planner
from benchmarks.cases import DATA
from benchmarks.report import seconds, table

EXAMPLE = Path(__file__).resolve().parents[1] / "missions" / "example" / "scenario.toml"
FLOOR = ("python -c 'import numpy, scipy.spatial'", ["-c", "import numpy, scipy.spatial"])
DATASET1_FLAGS = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25",
                  "--theta", "30", "--delta", "0.001"]  # fmt: skip
DATASET2_FLAGS = ["--alpha1", "20", "--alpha2", "10", "--beta1", "15", "--beta2", "20",
                  "--theta", "20", "--delta", "0.001"]  # fmt: skip
# (label, arguments after `python -m gcs_planner`)
COMMANDS = (
    ("gcs-planner plan dataset2.xlsx <Table 2 flags> --json (defaults: R 200 m, 3 objectives)",
     ["plan", str(DATA / "dataset2.xlsx"), *DATASET2_FLAGS, "--json"]),
    ("gcs-planner --help", ["--help"]),
    ("gcs-planner plan dataset1.xlsx --json (defaults: R 200 m, 3 objectives)",
     ["plan", str(DATA / "dataset1.xlsx"), *DATASET1_FLAGS, "--json"]),
    ("gcs-planner plan missions/example/scenario.toml --json (a CSV: no openpyxl)",
     ["plan", str(EXAMPLE), "--json"]),
    ("gcs-planner plan dataset1.xlsx --json --turn-radius 0 --objectives length,corrections",
     ["plan", str(DATA / "dataset1.xlsx"), *DATASET1_FLAGS, "--json", "--turn-radius", "0",
      "--objectives", "length,corrections"]),
)  # fmt: skip


@dataclass(frozen=True)
class Timing:
    label: str
    wall: float  # median whole-process seconds
    cpu: float  # median user + system CPU seconds of the process: less swayed by the load
    search: float | None  # median search seconds reported by the plan, if it is a plan


def _cpu_of_children() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _once(args: list[str], env: dict[str, str] | None = None) -> tuple[float, float, float | None]:
    cpu_before = _cpu_of_children()
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, *args], capture_output=True, text=True, check=True, timeout=600, env=env
    )
    wall = time.perf_counter() - started
    cpu = _cpu_of_children() - cpu_before
    search = None
    if "--json" in args:
        search = float(json.loads(done.stdout)["stats"]["search_seconds"])
    return wall, cpu, search


def _after_a_first_plan(cache: Path) -> dict[str, str]:
    """The environment of a user who never ran ``gcs-planner compile``: numba's cache the
    empty folder ``cache``, one first plan (it starts the background compile), and the wait
    for that compile to end (its lock file: gcs_planner/runtime/background_compile.py)."""
    from gcs_planner.runtime import background_compile

    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), background_compile.VARIABLE: "1"}
    env.pop("PYTEST_CURRENT_TEST", None)
    env.pop("GCS_PLANNER_COMPILE", None)
    _once(["-m", "gcs_planner", *COMMANDS[0][1]], env)
    lock = cache / "gcs-planner-compile.lock"
    if lock.exists():
        with lock.open("a") as f:
            fcntl.flock(f, fcntl.LOCK_EX)  # returns once the background compile has ended
    env[background_compile.VARIABLE] = "0"
    return env


def run_startup(runs: int, fresh_cache: bool = True) -> list[Timing]:
    """Median wall and CPU time of the floor and of each command over ``runs`` interleaved
    rounds, with numba's cache filled as a first plan fills it (:func:`_after_a_first_plan`);
    ``fresh_cache`` False takes the cache as it is instead (a smoke run: filling a fresh one
    compiles every kernel, a minute of CPU)."""
    # pip compiles an installed package's bytecode; an editable checkout under
    # PYTHONDONTWRITEBYTECODE would recompile every module at every start instead.
    compileall.compile_dir(str(Path(gcs_planner.__file__).parent), quiet=1)
    if not fresh_cache:
        from gcs_planner.runtime import background_compile

        return _rounds(runs, {**os.environ, background_compile.VARIABLE: "0"})
    with tempfile.TemporaryDirectory(prefix="gcs-planner-startup-") as cache:
        env = _after_a_first_plan(Path(cache))
        return _rounds(runs, env)


def _rounds(runs: int, env: dict[str, str]) -> list[Timing]:
    jobs = [(FLOOR[0], FLOOR[1])] + [(label, ["-m", "gcs_planner", *a]) for label, a in COMMANDS]
    _once(jobs[0][1], env)  # warm the file cache once, for every job alike
    walls: dict[str, list[float]] = {label: [] for label, _ in jobs}
    cpus: dict[str, list[float]] = {label: [] for label, _ in jobs}
    searches: dict[str, list[float]] = {label: [] for label, _ in jobs}
    for _ in range(runs):
        for label, args in jobs:
            wall, cpu, search = _once(args, env)
            walls[label].append(wall)
            cpus[label].append(cpu)
            if search is not None:
                searches[label].append(search)
    return [
        Timing(
            label,
            statistics.median(walls[label]),
            statistics.median(cpus[label]),
            statistics.median(searches[label]) if searches[label] else None,
        )
        for label, _ in jobs
    ]


def render(rows: list[Timing]) -> str:
    floor = rows[0]
    out = []
    for r in rows:
        above, cpu_above = r.wall - floor.wall, r.cpu - floor.cpu
        first = r is floor
        out.append(
            [
                f"`{r.label}`",
                seconds(r.wall),
                "–" if first else f"{above:+.2f} s",
                seconds(r.search),
                "–" if r.search is None else f"{above - r.search:+.2f} s",
                seconds(r.cpu),
                "–" if first else f"{cpu_above:+.2f} s",
            ]
        )
    head = [
        "process",
        "wall (median)",
        "above the floor",
        "search",
        "above floor + search",
        "CPU (user + sys)",
        "CPU above the floor (search included)",
    ]
    return table(head, out)


def main() -> None:
    print(render(run_startup(5)))


if __name__ == "__main__":
    main()
