"""Running a sweep on Dask: every unfinished cell one task, results saved as cells finish.

By default the sweep starts a ``distributed.LocalCluster`` of worker processes on this machine
and closes it at the end; given a scheduler address it submits to that cluster instead and
leaves it running. Dask does the rest a home-made pool would have to: a worker that dies has its
tasks run again elsewhere (its nanny starts a new one), and the dashboard shows the cluster.

The table is saved while cells finish, at the end, and when the sweep is interrupted, so a
resumed sweep loses at most the cells finished since the last save. Saves come every
``save_interval`` seconds, or less often once a table is so large that rewriting it would take
more than 1/``SAVE_BUDGET`` of the sweep's time: the rewrite grows with the table, the planning
does not, and on a small machine the client shares its cores with the workers.

The local cluster is started with Dask's sampling profiler, event-loop watchdog and system
monitors slowed down (``LEAN_CLUSTER``): at their defaults (a stack sample every 10 ms, a loop
tick every 20 ms, ...) they cost the workers and the scheduler some 10 % of a planning task's CPU
time on two cores. The dashboard keeps every page, with coarser profiles and plots. A cluster
given by address keeps its own configuration.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from gcs_planner.errors import InputError
from gcs_planner.runtime.progress import Counter
from gcs_planner.sweep.batch import Batcher, error_row, run_batch
from gcs_planner.sweep.cells import Cell, expand
from gcs_planner.sweep.spec import ClusterSpec, SweepSpec, read_spec
from gcs_planner.sweep.task import run_cell
from gcs_planner.sweep.workers import (
    NoWorkersError,
    WorkerVersionError,
    check_versions,
    wait_for_workers,
)

SUMMARY_PNG = "summary.png"
# Tasks handed to the scheduler at a time, at most: two per worker thread keep every worker busy
# (.batch sizes them); the cap keeps a huge cluster's scheduler from holding too many.
IN_FLIGHT = 10_000
DEFAULT_WORKERS = 2
# At most 1/SAVE_BUDGET of the sweep's wall time goes to rewriting the result table.
SAVE_BUDGET = 50
# Dask settings of the local cluster the sweep starts (see the module's docstring): an idle
# cluster's own housekeeping is a share of a small machine's CPU (docs/sweeps.md, "Speed").
LEAN_CLUSTER = {
    "distributed.worker.profile.interval": "100ms",  # default 10ms
    "distributed.admin.tick.interval": "1s",  # default 20ms; a stall is still reported at 3s
    # The dashboard's system page (CPU, memory, network, disk of each process) every 2 s, not
    # 0.5 s; the nannies check their worker's memory every 0.5 s, not 0.1 s. Together they
    # were a quarter of the scheduler process's event-loop time during a sweep.
    "distributed.admin.system-monitor.interval": "2s",
    "distributed.worker.memory.monitor-interval": "500ms",
    # Dask starts its workers with MALLOC_TRIM_THRESHOLD_=65536 so that freed memory goes back
    # to the system at once; fixing it also stops glibc from raising its mmap threshold, so
    # every array of the planner above 128 kB is mapped and unmapped afresh: 6-10 % more CPU
    # per cell (docs/sweeps.md). Its cells are small;
    # glibc's own adaptive thresholds serve. (None: Dask leaves the variable out.)
    "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
}
# The sweep's own local workers ignore SIGINT (see worker_setup): a terminal's Ctrl-C reaches
# the whole process group, and the client, not each worker, decides what a stop means.
LOCAL_WORKERS = {"distributed.worker.preload": ["gcs_planner.sweep.worker_setup"]}
# How often the client looks up from its wait for results: the Ctrl-C flag and the workers are
# checked at least this often, however long a cell takes.
POLL_S = 0.25
# How often, while no result comes, the client asks the scheduler how many workers it has.
WORKER_CHECK_S = 2.0
# A sweep with no worker at all for this long stops with a message, its table saved.
NO_WORKERS_TIMEOUT_S = 60.0
# How long --min-workers waits for its workers by default: batch jobs may queue for minutes.
MIN_WORKERS_TIMEOUT_S = 600.0
# Connecting to a scheduler across a cluster's network (or while it starts) takes seconds;
# an address that answers nothing for this long is a wrong one.
CONNECT_TIMEOUT_S = 20.0
# What the user's environment said before any Dask nanny of this process wrote Dask's value
# into it (a nanny sets its pre-spawn variables in its own process, for good).
_USER_MALLOC_TRIM = os.environ.get("MALLOC_TRIM_THRESHOLD_")


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped the sweep; its table is saved with ``saved`` cells in ``out``."""

    def __init__(self, saved: int, out: Path) -> None:
        self.saved = saved
        self.out = out
        super().__init__(f"interrupted, {saved} cells saved, resume with --resume")


@dataclass(frozen=True)
class SweepResult:
    out: Path
    cells: int  # in the spec
    skipped: int  # finished by an earlier run (--resume)
    ran: int  # finished by this run
    failed: int  # of those, status "error"
    infeasible: int
    seconds: float
    dashboard: str
    files: tuple[Path, ...]


def run_sweep(
    spec: SweepSpec | str | Path,
    out: str | Path,
    *,
    scheduler: str | None = None,
    workers: int = DEFAULT_WORKERS,
    threads_per_worker: int = 1,
    resume: bool = False,
    dashboard_address: str = "127.0.0.1:0",
    save_interval: float = 1.0,
    stream: TextIO | None = None,
    task: Callable[[Cell], list[dict]] = run_cell,
    quiet: bool = False,
    progress_stream: TextIO | None = None,
    no_workers_timeout: float = NO_WORKERS_TIMEOUT_S,
    prune: bool = False,
    retry_failed: bool = False,
    connect_timeout: float = CONNECT_TIMEOUT_S,
    scheduler_from: str = "--scheduler",
    min_workers: int = 0,
    min_workers_timeout: float = MIN_WORKERS_TIMEOUT_S,
) -> SweepResult:
    """Run the sweep ``spec`` (a SweepSpec or the path of its TOML) into the folder ``out``.

    ``scheduler``: the address of an existing Dask scheduler (``tcp://host:8786``), reached
    within ``connect_timeout`` seconds; without it the spec's [cluster] jobs are submitted
    (:mod:`.jobqueue`) or, without one, a LocalCluster of ``workers`` processes is started;
    either is closed at the end. ``scheduler_from`` is where the address came from, for the
    message when it cannot be reached. ``resume``: keep the finished cells of an earlier run
    in ``out`` and run only the others; it refuses a spec whose cells
    changed since (:mod:`.manifest`) unless ``prune``, which drops the rows of the cells no
    longer in it. ``retry_failed``: run the cells whose task failed again. ``stream``: where
    its messages go (None: nowhere). ``task`` runs one cell on a worker; it must be importable
    there. The cells done, failed and the time left are one line on ``progress_stream``
    (default stderr) when it is a terminal and ``quiet`` is False.

    Ctrl-C (SIGINT) saves the table and raises :class:`SweepInterrupted`; a scheduler without
    any worker for ``no_workers_timeout`` seconds, or with fewer than ``min_workers`` after
    ``min_workers_timeout``, saves it and raises :class:`NoWorkersError`; a worker with another
    planner version raises :class:`~.workers.WorkerVersionError`.
    """
    from gcs_planner.sweep.summary import summary_png
    from gcs_planner.sweep.table import CSV, PARQUET, ResultTable

    if not isinstance(spec, SweepSpec):
        spec = read_spec(spec)
    if workers < 1 or threads_per_worker < 1:
        raise InputError("workers and threads per worker must be >= 1", field="--workers")
    if min_workers < 0:
        raise InputError(f"must be >= 0 (got {min_workers})", field="--min-workers")
    out = Path(out)
    from gcs_planner.sweep.manifest import check_resume, write_manifest

    say = (lambda text: print(text, file=stream, flush=True)) if stream else (lambda text: None)
    table = ResultTable.open(out, resume)
    cells = expand(spec)
    if resume:
        for note in check_resume(out, spec, cells, table, prune):
            say(note)
    if retry_failed:
        retried = table.drop(table.failed())
        if retried:
            say(f"running the {retried} failed cells again")
    write_manifest(out, spec, cells)
    todo = [c for c in cells if c.key not in table.done]
    skipped = len(cells) - len(todo)
    say(f"sweep {spec.name}: {len(cells)} cells" + (f", {skipped} already done" if skipped else ""))

    started = time.perf_counter()
    ran, failed, infeasible, dashboard = 0, 0, 0, ""
    closing = None
    jobs = spec.cluster if scheduler is None else None
    if scheduler is not None and spec.cluster is not None:
        say(f"note: submitting to {scheduler} ({scheduler_from}): the spec's [cluster] is unused")
    if jobs is not None:
        # Batch jobs queue before they start: wait for them rather than count them as gone.
        min_workers = max(min_workers, 1)
    if todo:
        client, cluster = _connect(
            scheduler, workers, threads_per_worker, dashboard_address, connect_timeout,
            scheduler_from, jobs, spec.path,
        )  # fmt: skip
        try:
            dashboard = client.dashboard_link or ""
            if jobs is not None:
                from gcs_planner.sweep.jobqueue import describe

                where = describe(jobs)
            else:
                where = scheduler or f"a local cluster of {workers} worker processes"
            say(f"running on {where}; dashboard: {dashboard or '(none)'}")
            if min_workers:
                wait_for_workers(client, min_workers, min_workers_timeout, say)
            check_versions(client)
            progress = Counter("cells", len(todo), unit="cell", stream=progress_stream, quiet=quiet)
            try:
                ran, failed, infeasible = _run(
                    client, todo, table, task, progress, save_interval, no_workers_timeout
                )
            finally:
                progress.close()  # ends the line, interrupted or not, before anything is said
        except BaseException as exc:
            try:
                table.save()
            finally:
                _disconnect(client, cluster)
            if isinstance(exc, KeyboardInterrupt) and not isinstance(exc, SweepInterrupted):
                raise SweepInterrupted(len(table.done), out) from None
            if isinstance(exc, (NoWorkersError, WorkerVersionError)):
                raise type(exc)(
                    f"{exc}; {len(table.done)} cells saved in {out}, resume with --resume"
                ) from None
            raise
        table.save()
        # Stopping the workers is mostly waiting for their processes to exit: draw the
        # picture meanwhile rather than after.
        closing = threading.Thread(
            target=_disconnect, args=(client, cluster), name="sweep-close", daemon=True
        )
        closing.start()
    try:
        files = table.save() if not todo else (out / PARQUET, out / CSV)
        png = summary_png(table.rows, spec.swept, out / SUMMARY_PNG, spec.name)
    finally:
        if closing is not None:
            closing.join()
    return SweepResult(
        out=out,
        cells=len(cells),
        skipped=skipped,
        ran=ran,
        failed=failed,
        infeasible=infeasible,
        seconds=time.perf_counter() - started,
        dashboard=dashboard,
        files=(*files, png),
    )


@contextlib.contextmanager
def _malloc_trim(value: str | None) -> Iterator[None]:
    """MALLOC_TRIM_THRESHOLD_ as ``value`` (None: unset) while the workers are spawned (they
    inherit this process's environment), then as it was."""
    before = os.environ.get("MALLOC_TRIM_THRESHOLD_")
    if value is None:
        os.environ.pop("MALLOC_TRIM_THRESHOLD_", None)
    else:
        os.environ["MALLOC_TRIM_THRESHOLD_"] = value
    try:
        yield
    finally:
        if before is None:
            os.environ.pop("MALLOC_TRIM_THRESHOLD_", None)
        else:
            os.environ["MALLOC_TRIM_THRESHOLD_"] = before


def _connect(
    scheduler: str | None,
    workers: int,
    threads: int,
    dashboard_address: str,
    connect_timeout: float = CONNECT_TIMEOUT_S,
    scheduler_from: str = "--scheduler",
    jobs: ClusterSpec | None = None,
    spec_path: str = "",
):
    import dask
    from distributed import Client, LocalCluster

    if scheduler is None and jobs is not None:
        from gcs_planner.sweep.jobqueue import require_jobqueue, start_jobs

        require_jobqueue(spec_path)
        host = jobs.host or ""
        cluster = start_jobs(jobs, spec_path, dashboard_address=f"{host}:0")
        return Client(cluster), cluster
    if scheduler is None:
        # The scheduler reads these when it starts, each nanny hands them to its worker
        # process (and to a worker it restarts).
        from gcs_planner.sweep.worker_start import set_preload, worker_start_config

        settings = {**LEAN_CLUSTER, **LOCAL_WORKERS, **worker_start_config()}
        with dask.config.set(settings), _malloc_trim(_USER_MALLOC_TRIM):
            set_preload()
            cluster = LocalCluster(
                n_workers=workers,
                threads_per_worker=threads,
                processes=True,
                host="127.0.0.1",
                dashboard_address=dashboard_address,
                # Not even Dask's errors: stopping the cluster races with the workers'
                # heartbeats, which then print a traceback on Ctrl-C or at the end (Dask logs a
                # failed heartbeat as an error). A cell's failure is a row; the dashboard shows
                # the workers.
                silence_logs=logging.CRITICAL,
            )
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout=f"{connect_timeout}s"), None
    except (OSError, ValueError, TypeError) as exc:
        raise InputError(
            f"cannot reach the Dask scheduler {scheduler!r} within {connect_timeout:g} s: {exc}",
            field=scheduler_from,
        ) from None


def _disconnect(client, cluster) -> None:
    try:
        client.close()
    finally:
        if cluster is not None:
            # a job cluster whose jobs never started closes with an assertion inside Dask
            with contextlib.suppress(AssertionError):
                cluster.close()


def _run(
    client,
    todo: list[Cell],
    table,
    task,
    progress: Counter,
    save_interval: float,
    no_workers_timeout: float = NO_WORKERS_TIMEOUT_S,
):
    from distributed import as_completed

    token = uuid.uuid4().hex[:8]  # keys unique across sweeps sent to one long-lived scheduler
    workers = _WorkerWatch(client, no_workers_timeout)
    batcher = Batcher(todo, workers.threads)
    futures: dict = {}

    def submit() -> list:
        """Tasks until the window is full: two per worker thread (one running, one waiting
        on each), IN_FLIGHT at most; the first ones a cell each, to measure (.batch)."""
        batcher.threads = workers.threads
        new = []
        while len(futures) < min(IN_FLIGHT, batcher.probes):
            cells = batcher.next()
            if not cells:
                break
            key = f"sweep-{token}-{cells[0].index}-{len(cells)}-{cells[0].key}"
            future = client.submit(run_batch, task, cells, key=key)
            futures[future] = cells
            new.append(future)
        return new

    with _interrupt_flag() as interrupted:
        return _collect(
            submit, futures, batcher, as_completed, table, progress, save_interval, interrupted,
            workers,
        )  # fmt: skip


class _WorkerWatch:
    """Whether the scheduler has had no worker for ``timeout`` seconds, asked at most every
    WORKER_CHECK_S while the client waits: a sweep whose workers are all gone (a cluster's
    jobs ended, a scheduler started without any) would otherwise wait forever, silently."""

    def __init__(self, client, timeout: float) -> None:
        self.client = client
        self.timeout = timeout
        self.last_check = -float("inf")
        self.none_since: float | None = None
        nthreads = client.nthreads()
        self.known: set[str] = set(nthreads)  # checked when the sweep started
        self.threads = max(1, sum(nthreads.values()))  # the cluster's worker threads

    def check(self) -> None:
        now = time.monotonic()
        if now - self.last_check < min(WORKER_CHECK_S, max(self.timeout / 4, 0.1)):
            return
        self.last_check = now
        try:
            nthreads = self.client.nthreads()
        except Exception:  # the scheduler itself is unreachable: the same wait, nothing runs
            nthreads = {}
        present = set(nthreads)
        if nthreads:
            self.threads = sum(nthreads.values())
        joined = present - self.known
        if joined:  # a worker that joined mid-sweep runs the same planner, or the sweep stops
            check_versions(self.client, sorted(joined))
            self.known |= joined
        if present:
            self.none_since = None
            return
        if self.none_since is None:
            self.none_since = now
        elif now - self.none_since >= self.timeout:
            raise NoWorkersError(f"no Dask worker for {self.timeout:g} s, the sweep stopped")

    def seen_results(self) -> None:
        self.none_since = None


@contextlib.contextmanager
def _interrupt_flag() -> Iterator[threading.Event]:
    """An event set by Ctrl-C (SIGINT) while the sweep collects its cells. A KeyboardInterrupt
    raised wherever the main thread happens to be waiting could be swallowed inside Dask's
    client (a sweep so interrupted ran to its end); the flag is checked between cells instead,
    and the sweep stops there, saving what it has."""
    flag = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield flag  # signals reach the main thread only
        return
    previous = signal.signal(signal.SIGINT, lambda signum, frame: flag.set())
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)


def _collect(
    submit, futures, batcher, as_completed, table, progress, save_interval, interrupted, workers
):
    flow = as_completed(submit())
    done = failed = infeasible = 0
    last_save = time.perf_counter()
    wait = save_interval
    while not flow.is_empty():
        if interrupted.is_set():
            raise KeyboardInterrupt
        finished = flow.next_batch(block=False)
        workers.check()  # at most every WORKER_CHECK_S: new workers' versions, none left
        if not finished:
            # A wait with a timeout, not as_completed's blocking one: the Ctrl-C flag and the
            # workers are looked at while a long cell runs, not only when one finishes.
            with flow.thread_condition:
                flow.thread_condition.wait(timeout=POLL_S)
            continue
        workers.seen_results()
        for future in finished:
            cells = futures.pop(future)
            try:
                results = future.result()
            except Exception as exc:  # the task itself could not run (its worker kept dying)
                results = [[error_row(cell, exc)] for cell in cells]
            future.release()
            for rows in results:
                batcher.observe(rows)
                if table.add(rows):
                    done += 1
                    status = rows[0].get("status")
                    failed += status == "error"
                    infeasible += status == "infeasible"
            # the next tasks sized by what these cells cost
            for new in submit():
                flow.add(new)
        progress.update(done, failed=failed)
        if time.perf_counter() - last_save >= wait:
            t0 = time.perf_counter()
            table.save()
            last_save = time.perf_counter()
            wait = max(save_interval, SAVE_BUDGET * (last_save - t0))
    if interrupted.is_set():
        raise KeyboardInterrupt
    return done, failed, infeasible
