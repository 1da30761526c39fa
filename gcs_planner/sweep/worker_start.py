"""How the local cluster starts its worker processes: forked from a server that has already
imported Dask and the planner, not spawned as fresh interpreters.

Dask spawns each worker by default: a new interpreter that imports Dask, numpy, scipy and then,
at its first cell, the planner and the dry run (about 3 s of CPU each); two workers on two cores
took 6.7 s to start and 0.7 s to stop (measured with the worker preload, under load). Python's
forkserver imports those modules once, in one process, and forks each worker from it: 3.8 s and
0.05 s on the same machine, and the workers' first cells no longer import anything. Forking
from the forkserver is safe where forking from this process is not: the forkserver runs no
thread, this process runs the client's and the scheduler's.

The forkserver is Python's, one per process and started at its first use; its preload is set
here before that. Where it is not available (Windows) the workers are spawned as before. The
method holds while the cluster starts: a worker that its nanny restarts later (after a crash)
is spawned, as Dask does by default, and runs the same preload.
"""

from __future__ import annotations

import multiprocessing

# Imported by the forkserver before it forks any worker: Dask's worker, the SIGINT rule of the
# sweep's own workers (worker_setup) and what a cell needs (warm).
PRELOAD = ("distributed", "gcs_planner.sweep.worker_setup", "gcs_planner.sweep.warm")


def start_method() -> str:
    """``forkserver`` where Python offers it, else ``spawn`` (Dask's default)."""
    return "forkserver" if "forkserver" in multiprocessing.get_all_start_methods() else "spawn"


def worker_start_config() -> dict[str, str]:
    """Dask configuration for the local cluster's workers; call :func:`set_preload` under it."""
    return {"distributed.worker.multiprocessing-method": start_method()}


def set_preload() -> None:
    """The forkserver's preload set to :data:`PRELOAD` (under :func:`worker_start_config`).

    Dask sets its own list (Dask and its dependencies) at the first context it makes; set
    after that, ours stands. It takes effect only if the forkserver has not started yet in
    this process: a second sweep in the same process reuses the running one, already
    preloaded."""
    from distributed.utils import get_mp_context

    ctx = get_mp_context()
    if ctx.get_start_method() == "forkserver":
        ctx.set_forkserver_preload(list(PRELOAD))
