"""Cells grouped into Dask tasks that take about a second each, so that a cluster pays off.

A cell of a contest-sized scenario plans in 0.1-0.2 s; a Dask task costs the client, the
scheduler and the worker some milliseconds of CPU each (messages, bookkeeping, the result's
transfer), taken on a small machine from the very cores that plan. One task per cell made a
2-worker cluster slower than a loop. Grouped so that each task takes about
``TARGET_TASK_S``, that cost is a few per cent.

What a cell costs is not known before one has run (a scenario file may hold 20 points or
20,000): the first few cells go out one per task, and every later task is sized from the
median time of the cells finished so far (the worker-measured ``cell_seconds``, recent ones
weighing as much as old). Near the end the tasks shrink (guided self-scheduling: at most a
share of what is left per worker thread), so that the workers finish together rather than one
of them running a long last task alone.
"""

from __future__ import annotations

import math
import statistics
import time
from collections import deque
from collections.abc import Callable, Iterator

from gcs_planner.sweep.cells import Cell
from gcs_planner.sweep.task import cell_inputs, finish_row

# A task's planned duration: long enough that Dask's per-task cost is a few per cent of it,
# short enough that Ctrl-C loses little and the last tasks balance.
TARGET_TASK_S = 1.0
# Cells sent one per task, per worker thread, to measure what a cell costs.
PROBES_PER_THREAD = 2
# The median of this many latest cell times sizes the next task.
RECENT = 32
# Near the end a task holds at most 1/TAIL_SHARE of the cells left per worker thread.
TAIL_SHARE = 2


def run_batch(task: Callable[[Cell], list[dict]], cells: list[Cell]) -> list[list[dict]]:
    """Run ``task`` on each of ``cells`` (on a worker); each cell's rows. A cell whose task
    raises is an error row: the other cells of the task are kept."""
    out = []
    for cell in cells:
        started = time.perf_counter()
        try:
            out.append(task(cell))
        except Exception as exc:
            out.append([error_row(cell, exc, started)])
    return out


def error_row(cell: Cell, exc: BaseException, started: float | None = None) -> dict:
    """The one row of a cell whose task itself failed."""
    row = cell_inputs(cell)
    row.update(status="error", error=f"{type(exc).__name__}: {exc}".splitlines()[0])
    return finish_row(row, time.perf_counter() if started is None else started)


class Batcher:
    """Hands out the cells still to send in tasks sized by what the finished cells cost."""

    def __init__(self, cells: list[Cell], threads: int, target: float = TARGET_TASK_S) -> None:
        self._cells: Iterator[Cell] = iter(cells)
        self.left = len(cells)
        self.threads = max(1, threads)
        self.target = target
        self._recent: deque[float] = deque(maxlen=RECENT)

    @property
    def probes(self) -> int:
        """How many single-cell tasks to send first."""
        return PROBES_PER_THREAD * self.threads

    def observe(self, rows: list[dict]) -> None:
        """A finished cell's rows: its time on the worker sizes the next tasks."""
        seconds = [r["cell_seconds"] for r in rows if r.get("cell_seconds") is not None]
        if seconds:
            self._recent.append(max(seconds))

    def size(self) -> int:
        """Cells in the next task."""
        if not self._recent:
            return 1
        cost = statistics.median(self._recent)
        wanted = self.target / cost if cost > 0 else self.left
        tail = self.left // (TAIL_SHARE * self.threads)
        return max(1, min(math.ceil(wanted), tail, self.left))

    def next(self, size: int | None = None) -> list[Cell]:
        """The next task's cells (``size``, default :meth:`size`); empty when none are left."""
        batch = []
        for _ in range(self.size() if size is None else size):
            cell = next(self._cells, None)
            if cell is None:
                break
            batch.append(cell)
        self.left -= len(batch)
        return batch
