"""The workers a sweep may run on: enough of them, running this planner.

On a cluster the workers come and go on their own schedule (batch jobs wait in a queue, start,
reach their walltime); a sweep submitted before any has joined would sit in the scheduler with
nothing said. ``--min-workers N`` waits for N, saying so, for at most a given time, then stops
with a message (exit 4, as a scheduler with no worker at all does).

A worker that runs another version of gcs-planner plans another way (other kernels, other
defaults): its rows would sit beside the others' in one table with nothing to tell them apart.
Every worker is asked its version when the sweep starts and whenever a new one joins; a
mismatch stops the sweep naming the worker and both versions.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable

from gcs_planner import __version__
from gcs_planner.errors import GcsPlannerError

# How often the client asks the scheduler how many workers it has while waiting for them.
POLL_S = 0.5


class NoWorkersError(GcsPlannerError):
    """The scheduler had no worker (or too few) for too long; the table is saved. Exit 4, as
    a link that failed (5 is a dry run lost by its replay)."""

    exit_code = 4


class WorkerVersionError(GcsPlannerError):
    """A worker runs another version of gcs-planner than this client (or none)."""

    exit_code = 2


def planner_version() -> str:
    """The version of gcs-planner imported in this process (run on each worker)."""
    import gcs_planner

    return str(gcs_planner.__version__)


def wait_for_workers(
    client, count: int, timeout: float, say: Callable[[str], None] = lambda text: None
) -> int:
    """Wait until the scheduler has ``count`` workers, at most ``timeout`` seconds; returns how
    many it has. Raises :class:`NoWorkersError` when too few joined in time."""
    have = len(client.nthreads())
    if have >= count:
        return have
    say(f"waiting for {count} Dask workers ({have} so far, at most {timeout:g} s)")
    deadline = time.monotonic() + timeout
    while have < count:
        if time.monotonic() >= deadline:
            raise NoWorkersError(
                f"{have} of the {count} Dask workers asked for (--min-workers) joined within "
                f"{timeout:g} s, the sweep stopped"
            )
        time.sleep(POLL_S)
        have = len(client.nthreads())
    say(f"{have} Dask workers joined")
    return have


def check_versions(client, workers: Iterable[str] | None = None) -> None:
    """Refuse a worker (of ``workers``, default all) whose gcs-planner is not this one's."""
    names = None if workers is None else list(workers)
    if names == []:
        return
    try:
        versions = client.run(planner_version, workers=names, on_error="return")
    except (OSError, TimeoutError):  # a worker gone meanwhile: the next check sees the rest
        return
    for address, version in sorted(versions.items()):
        if isinstance(version, BaseException):
            if isinstance(version, (OSError, TimeoutError)):
                continue
            raise WorkerVersionError(
                f"Dask worker {address} cannot run gcs-planner ({type(version).__name__}: "
                f"{version}); install gcs-planner {__version__} there"
            )
        if version != __version__:
            raise WorkerVersionError(
                f"Dask worker {address} runs gcs-planner {version}, this client {__version__}: "
                "install the same version on every worker"
            )
