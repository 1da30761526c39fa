"""Task functions for the sweep's cluster tests: the real cell task, wrapped to leave a trace
on disk (the workers are other processes) or to kill its own worker process once.

They are pickled by value (cloudpickle) so a worker needs nothing of the tests on its path.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

from gcs_planner.sweep import Cell, run_cell


def logged(cell: Cell, *, log: str) -> list[dict]:
    """run_cell, then one line with the cell's key appended to ``log`` (once it has finished)."""
    rows = run_cell(cell)
    with open(log, "a", encoding="utf-8") as f:
        f.write(cell.key + "\n")
    return rows


def killing_once(cell: Cell, *, victim: int, marker: str, log: str) -> list[dict]:
    """Cell ``victim`` kills the worker process running it the first time (the marker file says
    it has); every other run, and that cell's second run, is the real task."""
    if cell.index == victim and not Path(marker).exists():
        Path(marker).write_text(str(os.getpid()), encoding="utf-8")
        os.kill(os.getpid(), signal.SIGKILL)
    return logged(cell, log=log)


def with_dask_settings(cell: Cell, *, log: str) -> list[dict]:
    """run_cell, then the Dask settings its worker process runs with, one line in ``log``."""
    import dask

    rows = run_cell(cell)
    keys = ("distributed.worker.profile.interval", "distributed.admin.tick.interval")
    trim = os.environ.get("MALLOC_TRIM_THRESHOLD_", "unset")
    with open(log, "a", encoding="utf-8") as f:
        f.write(" ".join(str(dask.config.get(k)) for k in keys) + f" trim={trim}\n")
    return rows


def failing_once(cell: Cell, *, victim: int, marker: str) -> list[dict]:
    """Cell ``victim`` raises the first time it runs (the marker file says it has)."""
    if cell.index == victim and not Path(marker).exists():
        Path(marker).write_text("failed", encoding="utf-8")
        raise RuntimeError("a transient failure")
    return run_cell(cell)


def stated_cost(cell: Cell, *, seconds: float, log: str) -> list[dict]:
    """A cell that plans nothing and says it took ``seconds`` on the worker (what the sweep
    sizes its tasks by); logs the Dask task that ran it and the cell's key."""
    from distributed import get_worker

    from gcs_planner.sweep.task import cell_inputs

    row = {**cell_inputs(cell), "status": "ok", "error": "", "cell_seconds": seconds}
    row.update(route=0, chosen=True, length=1000.0 + cell.index, corrections=1)
    with open(log, "a", encoding="utf-8") as f:
        f.write(f"{get_worker().get_current_task()} {cell.key}\n")
    return [row]


def held(cell: Cell, *, started: str, release: str) -> list[dict]:
    """run_cell, but cell 0 first says it started (the file ``started``) and waits until the
    file ``release`` exists (at most 300 s: a hang guard, not a timing)."""
    import time

    if cell.index == 0:
        Path(started).write_text("started", encoding="utf-8")
        deadline = time.monotonic() + 300
        while not Path(release).exists() and time.monotonic() < deadline:
            time.sleep(0.05)
    return run_cell(cell)
