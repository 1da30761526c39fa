"""One measurement of one method on one scenario, in a fresh process.

A fresh process per (method, scenario, run) makes the peak resident memory the method's own
(plus the same interpreter, numpy and scipy baseline for every method, which is reported apart),
and lets the parent enforce a time limit by killing it. The child loads everything first, then
runs the method once, timing only the method, and prints one JSON line. A run is over the limit
if the child reports more than the limit, or if it is still running ``STARTUP_S`` after it (the
time allowed for imports and loading the scenario), when it is killed.

    python -m benchmarks.worker '{"method": "project", "spec": "random-300"}'
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.cases import load_case
from benchmarks.plain import plain_front

# Imported up front by every method so that the baseline memory is the same for all of them.
from gcs_planner.baselines.milp import MilpNotProvenError, milp_front
from gcs_planner.core.search import straight_front

METHODS = ("project", "project-numpy", "plain", "milp", "nsga2")
ROOT = Path(__file__).resolve().parents[1]
STARTUP_S = 20.0  # imports and loading a workbook take about a second


@dataclass
class Measurement:
    """What one child reported. ``front`` is [(length, corrections, route)]; ``note`` says
    what is not plain (a MILP not proven, NSGA-II's generations)."""

    seconds: float
    rss_base_mib: float
    rss_peak_mib: float
    front: list[tuple[float, int, tuple[int, ...]]]
    note: str = ""
    extra: dict = field(default_factory=dict)

    @property
    def rss_own_mib(self) -> float:
        return max(0.0, self.rss_peak_mib - self.rss_base_mib)


def _rss_mib() -> float:
    # ru_maxrss is in KiB on Linux: the high-water mark of this process so far.
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _run(job: dict) -> dict:
    scenario = load_case(job["spec"])
    base = _rss_mib()
    method, limit = job["method"], float(job.get("time_limit", 120.0))
    note, extra = "", {}
    t0 = time.perf_counter()
    if method in ("project", "project-numpy"):
        # "project" decides by size (numba kernels from 3,000 points, their compiled code loaded
        # from numba's cache in this fresh process, which the time includes); "project-numpy"
        # is the numpy engine alone, for the comparison.
        result = straight_front(scenario, compiled=False if method == "project-numpy" else None)
        front = [(fp.length, fp.corrections, fp.points) for fp in result.front]
        extra = {"labels": result.stats.labels, "arcs": result.stats.arcs}
    elif method == "plain":
        front = plain_front(scenario)
    elif method == "milp":
        try:
            front = milp_front(scenario, time_limit=limit)
        except MilpNotProvenError as exc:
            front, note = exc.partial, f"not proven: {exc}"
    elif method == "nsga2":
        from gcs_planner.baselines.nsga2 import nsga2_front

        res = nsga2_front(
            scenario, seed=int(job["seed"]), n_gen=10**9, time_budget=float(job["budget"])
        )
        front = res.front
        extra = {"generations": res.generations, "evaluations": res.evaluations}
    else:
        raise ValueError(f"unknown method {method!r}")
    seconds = time.perf_counter() - t0
    return {
        "seconds": seconds,
        "rss_base_mib": base,
        "rss_peak_mib": _rss_mib(),
        "front": [[float(length), int(k), [int(p) for p in route]] for length, k, route in front],
        "note": note,
        "extra": extra,
    }


def measure(
    method: str,
    spec: str,
    time_limit: float | None,
    startup_s: float = STARTUP_S,
    **options: object,
) -> Measurement | None:
    """Run ``method`` on ``spec`` in a child process; None if it passed ``time_limit`` seconds
    (a child still running ``startup_s`` after the limit is killed). ``options``: ``seed`` and
    ``budget`` for NSGA-II."""
    job = {"method": method, "spec": spec, "time_limit": time_limit or 1e9, **options}
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    proc = subprocess.Popen(
        [sys.executable, "-m", "benchmarks.worker", json.dumps(job)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=ROOT,
        env=env,
    )
    try:
        out, err = proc.communicate(timeout=None if time_limit is None else time_limit + startup_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        return None
    if proc.returncode != 0:
        raise RuntimeError(f"{method} on {spec} failed (exit {proc.returncode}): {err.strip()}")
    data = json.loads(out.strip().splitlines()[-1])
    if time_limit is not None and data["seconds"] > time_limit:
        return None
    data["front"] = [(length, k, tuple(route)) for length, k, route in data["front"]]
    return Measurement(**data)


def main() -> None:
    print(json.dumps(_run(json.loads(sys.argv[1]))), flush=True)


if __name__ == "__main__":
    main()
