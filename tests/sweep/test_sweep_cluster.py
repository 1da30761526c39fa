"""The sweep on a real dask.distributed cluster (on 127.0.0.1, no mocks): the same rows as
planning each cell alone, a failing cell recorded while the rest finish, --resume running no
finished cell twice, a killed worker's cells run again with nothing lost, and the command line
on its own local cluster and on a separately started scheduler.

Where the subject is the sweep's own logic (rows, resume, failures, task sizes, progress) the
cluster is one of worker threads in this process, shared by the module: what the sweep does
with its results does not depend on where its workers run, and a worker process costs seconds
of CPU to start. Separate processes are started where they are the subject: a worker killed, a
worker of another version, Ctrl-C on the terminal's process group, the sweep's own forked
workers, and a scheduler and workers started with the `dask` command; one worker where two
are not the subject. A command line's bad input is checked in this process (``main``), its
exit code and one line the same as a subprocess's; Dask's own failures (no workers, a
scheduler out of reach) are checked in a real subprocess, whose whole stderr is one line.

No timing is asserted; every wait is for an event, with a generous deadline.
"""

from __future__ import annotations

import functools
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

import cloudpickle
import pytest
from distributed import LocalCluster
from support import sweep_tasks
from support.paths import MISSIONS, TESTS
from support.said import Said

from gcs_planner.cli import main
from gcs_planner.core.planner import plan
from gcs_planner.errors import InputError
from gcs_planner.scenario.generate import DATASET1, random_scenario
from gcs_planner.scenario.readers import load_scenario
from gcs_planner.sweep import expand, read_results, read_spec, run_sweep, runner
from gcs_planner.sweep.runner import SweepResult
from gcs_planner.sweep.table import PARQUET, ResultTable

cloudpickle.register_pickle_by_value(sweep_tasks)

EXAMPLE_SCENARIO = MISSIONS / "example" / "scenario.toml"
BIN = Path(sys.executable).parent
DEADLINE_S = 300.0
SMALL_BOX = "[40000, 20000, 2000]"


def threaded_cluster(workers: int) -> LocalCluster:
    """A scheduler and ``workers`` workers of one thread each, all in this process."""
    return LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=False,
        protocol="tcp",  # other processes reach it too: a command, a `dask worker`
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",
    )


@pytest.fixture(scope="module")
def cluster():
    """Two worker threads in this process, for the tests of the sweep's own logic."""
    with threaded_cluster(2) as c:
        yield c


@pytest.fixture(scope="module")
def empty_scheduler():
    """A scheduler in this process that never has a worker, reached by a command's subprocess
    over 127.0.0.1 as any other."""
    with threaded_cluster(0) as c:
        yield c.scheduler_address


def write_spec(tmp_path: Path, text: str, name: str = "spec.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def small_spec(
    tmp_path: Path, seeds: int = 3, deltas: str = "[0.001, 0.0011]", corrections: int = 24
) -> Path:
    return write_spec(
        tmp_path,
        f"""
[[scenarios]]
file = "{EXAMPLE_SCENARIO}"
[[scenarios]]
generate = "random"
corrections = {corrections}
seeds = {{ first = 1, count = {seeds} }}
box = {SMALL_BOX}
[grid]
delta = {deltas}
[plan]
objectives = ["length", "corrections"]
""",
    )


def by_cell(rows: list[dict]) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {}
    for r in rows:
        out.setdefault(r["cell_key"], []).append(r)
    return out


def logged_keys(log: Path) -> Counter:
    return Counter(log.read_text().split()) if log.exists() else Counter()


def test_sweep_gives_the_rows_of_planning_each_cell_alone(tmp_path: Path, cluster) -> None:
    spec_path = write_spec(
        tmp_path,
        f"""
[[scenarios]]
file = "{EXAMPLE_SCENARIO}"
[[scenarios]]
generate = "random"
corrections = 30
seeds = [5, 6]
box = {SMALL_BOX}
[grid]
turn_radius = [0, 200]
objectives = [["length", "corrections"], ["length", "corrections", "probability"]]
""",
    )
    result = run_sweep(spec_path, tmp_path / "out", scheduler=cluster.scheduler_address)
    assert (result.cells, result.ran, result.failed) == (12, 12, 0)
    rows = read_results(tmp_path / "out")
    cells = by_cell(rows)
    assert len(cells) == 12
    for cell in expand(read_spec(spec_path)):
        values = dict(cell.values)
        # Planned here, independently of the sweep's task: read or generate, override, plan.
        if cell.index < 4:
            scenario = load_scenario(EXAMPLE_SCENARIO, {"turn_radius": values["turn_radius"]})
        else:
            seed = 5 if cell.index < 8 else 6
            scenario = random_scenario(
                30, seed, params=DATASET1, box=(40000.0, 20000.0, 2000.0)
            ).with_params(turn_radius=values["turn_radius"])
        alone = plan(scenario, objectives=values["objectives"])
        got = sorted(cells[cell.key], key=lambda r: r["route"])
        assert [r["route_ids"] for r in got] == [" ".join(r.ids()) for r in alone.routes]
        assert [r["length"] for r in got] == pytest.approx([r.length for r in alone.routes])
        assert [r["corrections"] for r in got] == [r.corrections for r in alone.routes]
        assert [r["probability"] for r in got] == pytest.approx(
            [r.probability for r in alone.routes]
        )
        assert [r["gap"] for r in got] == pytest.approx(list(alone.gaps()), abs=1e-6)
        assert [r["chosen"] for r in got] == [i == alone.chosen for i in range(len(got))]
        assert all(r["proven"] == alone.optimal and r["status"] == "ok" for r in got)
        assert all(r["objectives"] == ",".join(values["objectives"]) for r in got)
    assert (tmp_path / "out" / "results.csv").read_text().count("\n") == len(rows) + 1
    assert (tmp_path / "out" / "summary.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_failing_cell_is_recorded_and_the_others_finish(tmp_path: Path, cluster) -> None:
    (tmp_path / "points.csv").write_text(
        "id,x,y,z,kind,unreliable\n0,0,0,0,A,0\n1,5,5,5,V,7\n2,9,9,9,B,0\n"
    )
    (tmp_path / "bad.toml").write_text(
        'points = "points.csv"\n[parameters]\nalpha1 = 25\nalpha2 = 15\nbeta1 = 20\n'
        "beta2 = 25\ntheta = 30\ndelta = 0.001\n"
    )
    spec_path = write_spec(
        tmp_path,
        f"""
[[scenarios]]
generate = "random"
corrections = 24
seeds = [1, 2]
box = {SMALL_BOX}
[[scenarios]]
file = "bad.toml"
[[scenarios]]
file = "{EXAMPLE_SCENARIO}"
[grid]
turn_radius = [0, 200]
""",
    )
    result = run_sweep(spec_path, tmp_path / "out", scheduler=cluster.scheduler_address)
    assert (result.ran, result.failed) == (8, 2)
    cells = by_cell(read_results(tmp_path / "out"))
    assert len(cells) == 8
    failed = [rows for rows in cells.values() if rows[0]["status"] == "error"]
    assert len(failed) == 2
    for rows in failed:
        assert len(rows) == 1 and rows[0]["source"] == str(tmp_path / "bad.toml")
        assert "row 3" in rows[0]["error"] and "unreliable" in rows[0]["error"]
        assert rows[0]["length"] is None
    ok = [rows for rows in cells.values() if rows[0]["status"] == "ok"]
    assert len(ok) == 6 and all(r["length"] > 0 for rows in ok for r in rows)


def test_resume_runs_no_finished_cell_twice(tmp_path: Path, cluster) -> None:
    log = tmp_path / "ran.log"
    task = functools.partial(sweep_tasks.logged, log=str(log))
    out = tmp_path / "out"
    # The first sweep finishes half of the cells (as an interrupted one would have) ...
    first = run_sweep(
        small_spec(tmp_path, deltas="[0.001]"), out, scheduler=cluster.scheduler_address, task=task
    )
    assert first.ran == 4
    before = {(r["cell_key"], r["route"]): r for r in read_results(out)}
    # ... without --resume a second sweep into the same folder is refused ...
    with pytest.raises(InputError, match="pass --resume"):
        run_sweep(small_spec(tmp_path), out, scheduler=cluster.scheduler_address, task=task)
    # ... and with it (and --prune: the spec grew) only the other half runs.
    second = run_sweep(
        small_spec(tmp_path),
        out,
        scheduler=cluster.scheduler_address,
        task=task,
        resume=True,
        prune=True,
    )
    assert (second.cells, second.skipped, second.ran) == (8, 4, 4)
    ran = logged_keys(log)
    assert len(ran) == 8 and set(ran.values()) == {1}
    after = {(r["cell_key"], r["route"]): r for r in read_results(out)}
    assert {k[0] for k in after} == set(ran)
    index = {c.key: c.index for c in expand(read_spec(small_spec(tmp_path)))}
    for key, row in before.items():
        # the earlier rows are kept as they were, not re-planned; numbered as the spec now
        assert after[key] == {**row, "cell": index[key[0]]}
    # A third resume has nothing left to do and submits nothing.
    third = run_sweep(small_spec(tmp_path), out, task=task, resume=True)
    assert (third.skipped, third.ran) == (8, 0)
    assert logged_keys(log) == ran


def test_a_killed_worker_s_cells_are_run_again_and_nothing_is_lost(tmp_path: Path) -> None:
    # Worker processes, one to kill: the sweep's own local cluster (forked workers, whose
    # nanny starts a new one), not the module's threads.
    log, marker = tmp_path / "ran.log", tmp_path / "killed"
    task = functools.partial(sweep_tasks.killing_once, victim=2, marker=str(marker), log=str(log))
    spec_path = small_spec(tmp_path, seeds=4)
    result = run_sweep(spec_path, tmp_path / "out", task=task)
    assert marker.exists()  # the victim did kill its worker
    killed_pid = int(marker.read_text())
    assert (result.ran, result.failed) == (10, 0)
    rows = read_results(tmp_path / "out")
    cells = by_cell(rows)
    assert len(cells) == 10 and all(r["status"] == "ok" for r in rows)
    # Every cell finished; one whose result was still held by the killed worker was computed
    # again (Dask recomputes lost results), but the table has each cell and route once.
    assert set(logged_keys(log)) == set(cells)
    assert all(n == 1 for n in Counter((r["cell_key"], r["route"]) for r in rows).values())
    victim = next(c for c in expand(read_spec(spec_path)) if c.index == 2)
    redone = cells[victim.key]
    assert all(int(r["worker"].rsplit(":", 1)[1]) != killed_pid for r in redone)
    alone = sweep_tasks.run_cell(victim)
    assert [r["length"] for r in redone] == pytest.approx([r["length"] for r in alone])
    assert [r["route_ids"] for r in redone] == [r["route_ids"] for r in alone]


def test_more_cells_than_the_in_flight_window_all_finish(
    tmp_path: Path, cluster, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The window is a tuning constant; a small one makes this sweep refill it many times.
    monkeypatch.setattr(runner, "IN_FLIGHT", 3)
    log = tmp_path / "ran.log"
    task = functools.partial(sweep_tasks.logged, log=str(log))
    result = run_sweep(
        small_spec(tmp_path, seeds=5),
        tmp_path / "out",
        scheduler=cluster.scheduler_address,
        task=task,
    )
    assert (result.cells, result.ran) == (12, 12)
    assert len(by_cell(read_results(tmp_path / "out"))) == 12
    assert set(logged_keys(log).values()) == {1} and len(logged_keys(log)) == 12


def test_own_local_cluster_runs_with_the_lean_dask_settings(tmp_path: Path, monkeypatch) -> None:
    # The cluster the sweep starts itself samples stacks and ticks its loop less often than
    # Dask's defaults, and its workers run without Dask's malloc trimming even when an earlier
    # Dask nanny in this process left MALLOC_TRIM_THRESHOLD_ in its environment (as one with
    # Dask's defaults does); this process's own configuration and environment are left as
    # they were.
    import dask

    monkeypatch.setattr(runner, "_USER_MALLOC_TRIM", None)
    monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", "65536")

    before = {k: dask.config.get(k) for k in runner.LEAN_CLUSTER}
    log = tmp_path / "settings.log"
    task = functools.partial(sweep_tasks.with_dask_settings, log=str(log))
    spec_path = small_spec(tmp_path, seeds=1, deltas="[0.001]")  # 2 cells
    result = run_sweep(spec_path, tmp_path / "out", task=task)
    assert (result.ran, result.failed) == (2, 0)
    lean = runner.LEAN_CLUSTER
    expected = (
        f"{lean['distributed.worker.profile.interval']} {lean['distributed.admin.tick.interval']}"
        " trim=unset"  # no MALLOC_TRIM_THRESHOLD_ in the workers' environment
    )
    assert log.read_text().splitlines() == [expected, expected]
    assert {k: dask.config.get(k) for k in runner.LEAN_CLUSTER} == before
    assert os.environ["MALLOC_TRIM_THRESHOLD_"] == "65536"


def wait_for(condition, what: str, proc: subprocess.Popen | None = None) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not condition():
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"process ended (code {proc.returncode}) before {what}")
        if time.monotonic() > deadline:
            raise AssertionError(f"gave up waiting for {what}")
        time.sleep(0.05)


def cli(*args: str) -> list[str]:
    return [str(BIN / "gcs-planner"), "sweep", *args]


# What differs between two runs of one cell: where and when it ran, how long it took.
VOLATILE = ("plan_seconds", "cell_seconds", "worker", "finished_at")


def comparable(rows: list[dict]) -> list[dict]:
    keep = [{k: v for k, v in r.items() if k not in VOLATILE} for r in rows]
    return sorted(keep, key=lambda r: (r["cell"], r["route"]))


def saved_cells(out: Path) -> int:
    """Cells in out's saved table (0 before the first save)."""
    if not (out / PARQUET).exists():
        return 0
    return len(by_cell(read_results(out)))


def test_terminal_ctrl_c_stops_saves_and_resume_gives_the_uninterrupted_table(
    tmp_path: Path, cluster, capsys: pytest.CaptureFixture
) -> None:
    # A terminal's Ctrl-C reaches the whole process group: the command and its local cluster's
    # worker processes. 40 cells of 400 points (some 0.2 s each): work left after the first
    # saved cell on any machine.
    cells = 40
    spec_path = small_spec(tmp_path, seeds=cells - 1, deltas="[0.001]", corrections=400)
    out = tmp_path / "out"
    proc = subprocess.Popen(
        cli(str(spec_path), "--out", str(out)),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # its own process group, as a terminal's foreground job
    )
    try:
        wait_for(lambda: saved_cells(out) > 0, "a saved cell", proc)
        os.killpg(os.getpgid(proc.pid), signal.SIGINT)
        _, err = proc.communicate(timeout=DEADLINE_S)
    finally:
        if proc.poll() is None:
            os.killpg(os.getpgid(proc.pid), signal.SIGKILL)
            proc.wait()
    assert proc.returncode == 130, err
    first = read_results(out)
    done_first = {r["cell_key"] for r in first}
    assert 0 < len(done_first) < cells
    assert f"interrupted, {len(done_first)} cells saved, resume with --resume" in err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err

    # The resume is the command again, in this process: the table it completes is the subject,
    # not where its cells run (the module's cluster).
    code = main(
        ["sweep", str(spec_path), "--out", str(out), "--resume",
         "--scheduler", cluster.scheduler_address]
    )  # fmt: skip
    again = capsys.readouterr()
    assert code == 0, again.err
    assert f"{len(done_first)} already done" in again.out
    assert f"{cells - len(done_first)} cells run" in again.out
    rows = read_results(out)
    keys = by_cell(rows)
    assert len(keys) == cells and all(r["status"] == "ok" for r in rows)
    kept = {(r["cell_key"], r["route"]): r for r in first}
    for r in rows:
        if r["cell_key"] in done_first:
            assert r == kept[(r["cell_key"], r["route"])]
    assert len(ResultTable.open(out, resume=True).rows) == len(rows)
    # the same table as a sweep nobody interrupted
    whole = tmp_path / "whole"
    run_sweep(spec_path, whole, scheduler=cluster.scheduler_address)
    assert comparable(rows) == comparable(read_results(whole))


def test_a_scheduler_without_workers_stops_the_sweep_with_a_message(
    tmp_path: Path, empty_scheduler: str
) -> None:
    # The address as a cluster's job script exports it, for Dask and for the sweep.
    done = subprocess.run(
        cli(str(small_spec(tmp_path)), "--out", str(tmp_path / "out"),
            "--no-workers-timeout", "3"),
        capture_output=True,
        text=True,
        timeout=DEADLINE_S,
        env={**os.environ, "DASK_SCHEDULER_ADDRESS": empty_scheduler},
    )  # fmt: skip
    assert done.returncode == 4, done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert "no Dask worker for 3 s" in done.stderr
    assert "0 cells saved" in done.stderr and "--resume" in done.stderr


def test_cli_on_a_separately_started_scheduler_and_workers(tmp_path: Path) -> None:
    scheduler_file = tmp_path / "scheduler.json"
    procs = [
        subprocess.Popen(
            [str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0",
             "--no-dashboard", "--scheduler-file", str(scheduler_file)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )
    ]  # fmt: skip
    try:
        wait_for(scheduler_file.exists, "the scheduler file", procs[0])
        wait_for(lambda: "address" in scheduler_file.read_text(), "the scheduler's address")
        import json

        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        procs.append(
            subprocess.Popen(
                [str(BIN / "dask"), "worker", address, "--nworkers", "1", "--nthreads", "1",
                 "--host", "127.0.0.1", "--no-dashboard"],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            )
        )  # fmt: skip
        done = subprocess.run(
            # the file the scheduler wrote, as batch jobs on a shared file system find it
            cli(str(small_spec(tmp_path)), "--out", str(tmp_path / "out"),
                "--scheduler-file", str(scheduler_file)),
            capture_output=True,
            text=True,
            timeout=DEADLINE_S,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert f"running on {address}" in done.stdout
        assert "8 cells run (0 failed, 0 infeasible)" in done.stdout
        rows = read_results(tmp_path / "out")
        assert len(by_cell(rows)) == 8 and all(r["status"] == "ok" for r in rows)
        # the workers were the separately started ones, not this test's or the command's
        pids = {int(r["worker"].rsplit(":", 1)[1]) for r in rows}
        assert os.getpid() not in pids and done.returncode == 0
        # and the scheduler is still there for the next sweep
        assert procs[0].poll() is None
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in reversed(procs):
            try:
                p.wait(timeout=60)
            except subprocess.TimeoutExpired:
                p.kill()


@pytest.mark.parametrize(
    "content, says",
    [
        (None, "cannot read it: No such file or directory"),
        ("{not json", "is not a Dask scheduler file (not JSON"),
        ('{"type": "Scheduler"}', "field 'address': names no scheduler address"),
        ('{"address": ""}', "field 'address': names no scheduler address"),
    ],
)
def test_cli_bad_scheduler_file_names_the_file(
    tmp_path: Path, content, says, capsys: pytest.CaptureFixture
) -> None:
    # Read before Dask is asked anything: the command in this process says what a subprocess
    # of it would (exit code, the one line).
    path = tmp_path / "scheduler.json"
    if content is not None:
        path.write_text(content)
    code = main(
        ["sweep", str(small_spec(tmp_path)), "--out", str(tmp_path / "out"),
         "--scheduler-file", str(path)]
    )  # fmt: skip
    done = capsys.readouterr()
    assert code == 2, done.err
    assert done.err.count("\n") == 1 and f"{path}" in done.err and says in done.err
    assert done.out == "" and not (tmp_path / "out").exists()


def test_cli_unreachable_scheduler_from_the_environment_says_where_it_came_from(
    tmp_path: Path,
) -> None:
    # A port nothing listens on: refused at once, or timed out after the one second asked.
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    done = subprocess.run(
        cli(str(small_spec(tmp_path)), "--out", str(tmp_path / "out"), "--connect-timeout", "1"),
        capture_output=True, text=True, timeout=DEADLINE_S,
        env={**os.environ, "DASK_SCHEDULER_ADDRESS": f"tcp://127.0.0.1:{port}"},
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1
    assert "field 'DASK_SCHEDULER_ADDRESS'" in done.stderr and "within 1 s" in done.stderr


def test_cli_bad_scheduler_address_is_one_line(tmp_path: Path) -> None:
    done = subprocess.run(
        cli(str(small_spec(tmp_path)), "--out", str(tmp_path / "out"), "--scheduler", "nope:::"),
        capture_output=True,
        text=True,
        timeout=DEADLINE_S,
    )
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "field '--scheduler'" in done.stderr


def test_resume_refuses_a_changed_spec_unless_pruned_and_renumbers(tmp_path: Path, cluster) -> None:
    out = tmp_path / "out"
    address = cluster.scheduler_address
    spec_path = small_spec(tmp_path, seeds=1, deltas="[0.001, 0.0011]")  # 2 scenarios x 2
    run_sweep(spec_path, out, scheduler=address)
    assert (out / "spec.toml").read_text() == spec_path.read_text()
    import json

    from gcs_planner import __version__

    record = json.loads((out / "sweep.json").read_text())
    assert record["planner_version"] == __version__ and len(record["cells"]) == 4
    before = by_cell(read_results(out))

    # 0.0011 replaced by 0.0012: 2 cells gone, 2 new
    small_spec(tmp_path, seeds=1, deltas="[0.001, 0.0012]")
    with pytest.raises(InputError) as refused:
        run_sweep(spec_path, out, scheduler=address, resume=True)
    message = str(refused.value)
    assert "spec changed" in message and "2 cells no longer in it, 2 new" in message
    assert "delta = [0.001, 0.0012]" in message and "--prune" in message
    assert by_cell(read_results(out)).keys() == before.keys()  # nothing touched

    done = run_sweep(spec_path, out, scheduler=address, resume=True, prune=True)
    assert (done.skipped, done.ran) == (2, 2)
    rows = read_results(out)
    cells = expand(read_spec(spec_path))
    assert by_cell(rows).keys() == {c.key for c in cells}
    # one number, one cell: the numbers are those of the spec given now
    index = {c.key: c.index for c in cells}
    assert all(r["cell"] == index[r["cell_key"]] for r in rows)
    assert len({(r["cell"], r["cell_key"]) for r in rows}) == len({r["cell"] for r in rows}) == 4
    # the same spec again, a comment added: not a change
    spec_path.write_text("# a comment\n" + spec_path.read_text())
    again = run_sweep(spec_path, out, scheduler=address, resume=True)
    assert (again.skipped, again.ran) == (4, 0)


def test_cli_changed_spec_on_resume_is_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    # Refused before any cluster is started: the command in this process (exit code, one line).
    out = tmp_path / "out"
    spec_path = small_spec(tmp_path, seeds=1)
    cells = expand(read_spec(spec_path))
    table = ResultTable(out)
    out.mkdir()
    from gcs_planner.sweep.manifest import write_manifest

    write_manifest(out, read_spec(spec_path), cells)
    table.add(sweep_tasks.run_cell(cells[0]))
    table.save()
    small_spec(tmp_path, seeds=2)
    code = main(["sweep", str(spec_path), "--out", str(out), "--resume"])
    done = capsys.readouterr()
    assert code == 2, done.err
    assert done.err.count("\n") == 1 and str(spec_path) in done.err
    assert "0 cells no longer in it, 2 new" in done.err and "seeds" in done.err


def test_retry_failed_runs_the_failed_cells_again(tmp_path: Path, cluster) -> None:
    out = tmp_path / "out"
    spec_path = small_spec(tmp_path, seeds=1)
    task = functools.partial(
        sweep_tasks.failing_once, victim=2, marker=str(tmp_path / "failed-once")
    )
    first = run_sweep(spec_path, out, scheduler=cluster.scheduler_address, task=task)
    assert first.failed == 1
    (failed,) = [r for r in read_results(out) if r["status"] == "error"]
    assert failed["cell"] == 2 and "a transient failure" in failed["error"]
    plain = run_sweep(spec_path, out, scheduler=cluster.scheduler_address, resume=True)
    assert plain.ran == 0  # a resume alone keeps the failure
    retried = run_sweep(
        spec_path, out, scheduler=cluster.scheduler_address, resume=True, retry_failed=True
    )
    assert (retried.skipped, retried.ran, retried.failed) == (3, 1, 0)
    rows = read_results(out)
    assert all(r["status"] == "ok" for r in rows) and len(by_cell(rows)) == 4


def with_test_tasks() -> dict:
    """The environment with the tests' folder on the path: a scheduler unpickles the task
    graph, and a test task of support.sweep_tasks names its module there."""
    path = os.pathsep.join(filter(None, [str(TESTS), os.environ.get("PYTHONPATH")]))
    return {**os.environ, "PYTHONPATH": path}


def start_workers(address: str, count: int, *extra: str) -> subprocess.Popen:
    """`dask worker ADDRESS --nworkers COUNT` on 127.0.0.1, as a user (or a batch job) starts it."""
    return subprocess.Popen(
        [str(BIN / "dask"), "worker", address, "--nworkers", str(count), "--nthreads", "1",
         "--host", "127.0.0.1", "--no-dashboard", *extra],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=with_test_tasks(),
    )  # fmt: skip


def stop(*procs: subprocess.Popen) -> None:
    for p in procs:
        p.terminate()
    for p in procs:
        try:
            p.wait(timeout=60)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()


def run_in_thread(sweep: Callable[[], SweepResult]) -> tuple[threading.Thread, dict]:
    """``sweep`` started in a thread; its result (or what it raised) lands in the dict."""
    outcome: dict = {}

    def run() -> None:
        try:
            outcome["result"] = sweep()
        except BaseException as exc:  # handed to the test's thread
            outcome["error"] = exc

    thread = threading.Thread(target=run)
    thread.start()
    return thread, outcome


def test_min_workers_waits_for_workers_that_join_later(tmp_path: Path) -> None:
    # A scheduler with no worker, and the two asked for added once the sweep says it waits
    # (threads of this process: the wait is the subject, not what the workers are).
    said = Said("waiting for 2 Dask workers (0 so far")
    with threaded_cluster(0) as empty:
        thread, outcome = run_in_thread(
            lambda: run_sweep(
                small_spec(tmp_path),
                tmp_path / "out",
                scheduler=empty.scheduler_address,
                min_workers=2,
                min_workers_timeout=DEADLINE_S,
                stream=said,
            )
        )
        try:
            wait_for(lambda: said.heard.is_set() or not thread.is_alive(), "the sweep to wait")
            assert said.heard.is_set(), (said.text(), outcome)
            assert not (tmp_path / "out" / PARQUET).exists()  # nothing ran without workers
            empty.scale(2)
        finally:
            thread.join(timeout=DEADLINE_S)
    assert not thread.is_alive() and "error" not in outcome, outcome
    result = outcome["result"]
    assert "2 Dask workers joined" in said.text()
    assert (result.ran, result.failed, result.infeasible) == (8, 0, 0)
    assert len(by_cell(read_results(tmp_path / "out"))) == 8


def test_min_workers_that_never_join_stop_the_sweep_with_a_message(
    tmp_path: Path, empty_scheduler: str
) -> None:
    done = subprocess.run(
        cli(str(small_spec(tmp_path)), "--out", str(tmp_path / "out"),
            "--scheduler", empty_scheduler, "--min-workers", "1", "--min-workers-timeout", "2"),
        capture_output=True, text=True, timeout=DEADLINE_S,
    )  # fmt: skip
    assert done.returncode == 4, done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert "0 of the 1 Dask workers asked for (--min-workers) joined within 2 s" in done.stderr
    assert "0 cells saved" in done.stderr and "--resume" in done.stderr


def test_a_worker_with_another_planner_version_is_refused(tmp_path: Path) -> None:
    from gcs_planner import __version__

    # A worker whose gcs-planner says it is another release, as an old install on one node would.
    preload = tmp_path / "other_version.py"
    preload.write_text("import gcs_planner\ngcs_planner.__version__ = '0.0.1-old'\n")
    # the scheduler in this process; the worker its own process (its own gcs_planner)
    with threaded_cluster(0) as empty:
        workers = start_workers(empty.scheduler_address, 1, "--no-nanny", "--preload", str(preload))
        try:
            done = subprocess.run(
                cli(str(small_spec(tmp_path)), "--out", str(tmp_path / "out"),
                    "--scheduler", empty.scheduler_address, "--min-workers", "1",
                    "--min-workers-timeout", str(DEADLINE_S)),
                capture_output=True, text=True, timeout=DEADLINE_S,
            )  # fmt: skip
        finally:
            stop(workers)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert "Dask worker tcp://127.0.0.1:" in done.stderr
    assert f"runs gcs-planner 0.0.1-old, this client {__version__}" in done.stderr
    assert read_results(tmp_path / "out") == []  # no cell ran on it


def test_progress_is_one_tqdm_line_on_stderr_and_failed_cells_do_not_break_chosen(
    tmp_path: Path, cluster, monkeypatch: pytest.MonkeyPatch
) -> None:
    import io

    import pyarrow.parquet as pq
    from support.terminal import FakeTerminal, screen

    # stderr a terminal, stdout the messages: the progress bar goes to stderr only, and what a
    # terminal shows after every redraw is one line with the final count (no stray tails).
    err, out = FakeTerminal(), io.StringIO()
    monkeypatch.setattr(sys, "stderr", err)
    (tmp_path / "bad.toml").write_text('points = "missing.csv"\n')
    spec_path = small_spec(tmp_path, seeds=2)
    spec_path.write_text(spec_path.read_text() + '[[scenarios]]\nfile = "bad.toml"\n')
    result = run_sweep(spec_path, tmp_path / "out", scheduler=cluster.scheduler_address, stream=out)
    assert (result.ran, result.failed) == (8, 2)
    rows = screen(err.getvalue())
    assert len(rows) == 1 and rows[0].startswith("cells: 100%") and "8/8" in rows[0], rows
    assert "failed=2" in rows[0]
    assert "\r" not in out.getvalue() and "cells:" not in out.getvalue()
    table = pq.read_table(tmp_path / "out" / PARQUET)
    # df[df.chosen] in pandas needs a column without nulls; one chosen route per planned cell
    assert table.column("chosen").null_count == 0
    chosen = table.filter(table.column("chosen")).to_pylist()
    assert len(chosen) == 6 and all(r["status"] == "ok" for r in chosen)
    assert table.schema.field("length").metadata == {b"unit": b"m"}


def test_cells_are_grouped_into_tasks_of_about_a_second_after_a_few_alone(
    tmp_path: Path, cluster
) -> None:
    # Cells that say they took 0.1 s each: after the first few (one per task, to measure),
    # each task holds about TARGET_TASK_S of cells, fewer near the end (the tail's share).
    from gcs_planner.sweep import batch

    log = tmp_path / "tasks.log"
    task = functools.partial(sweep_tasks.stated_cost, seconds=0.1, log=str(log))
    spec_path = small_spec(tmp_path, seeds=99, deltas="[0.001]")  # 100 cells
    result = run_sweep(spec_path, tmp_path / "out", scheduler=cluster.scheduler_address, task=task)
    assert (result.ran, result.failed) == (100, 0)
    tasks: dict[str, list[str]] = {}
    for line in log.read_text().splitlines():
        key, cell = line.split()
        tasks.setdefault(key, []).append(cell)
    cells = [c for group in tasks.values() for c in group]
    assert sorted(cells) == sorted(c.key for c in expand(read_spec(spec_path)))  # each once
    # The task keys carry the first cell's number: in the order the cells were handed out.
    sizes = [len(g) for _, g in sorted(tasks.items(), key=lambda kv: int(kv[0].split("-")[2]))]
    threads = 2
    probes = batch.PROBES_PER_THREAD * threads
    assert sizes[:probes] == [1] * probes
    per_task = round(batch.TARGET_TASK_S / 0.1)
    assert max(sizes) == per_task and sizes[probes] == per_task
    assert sizes[-1] < per_task  # the last tasks shrink so that the workers end together
    assert len(sizes) < 100 / 4
    assert len(by_cell(read_results(tmp_path / "out"))) == 100


def test_a_worker_with_another_version_joining_mid_sweep_stops_it(tmp_path: Path) -> None:
    from gcs_planner.sweep.workers import WorkerVersionError

    preload = tmp_path / "other_version.py"
    preload.write_text("import gcs_planner\ngcs_planner.__version__ = '0.0.1-old'\n")
    started, release = tmp_path / "started", tmp_path / "release"
    task = functools.partial(sweep_tasks.held, started=str(started), release=str(release))
    # The sweep's first worker a thread of this process; the one that joins mid-sweep its own
    # process, with its own gcs_planner.
    with threaded_cluster(1) as first:
        address = first.scheduler_address
        thread, outcome = run_in_thread(
            lambda: run_sweep(
                small_spec(tmp_path),
                tmp_path / "out",
                scheduler=address,
                task=task,
                min_workers=1,
                min_workers_timeout=DEADLINE_S,
            )
        )
        procs = []
        try:
            wait_for(lambda: started.exists() or not thread.is_alive(), "the first cell to start")
            assert started.exists(), outcome
            procs.append(start_workers(address, 1, "--no-nanny", "--preload", str(preload)))
            thread.join(timeout=DEADLINE_S)
            assert not thread.is_alive(), "the sweep did not stop"
        finally:
            release.write_text("go")
            thread.join(timeout=DEADLINE_S)
            stop(*procs)
    error = outcome.get("error")
    assert isinstance(error, WorkerVersionError), outcome
    assert "Dask worker tcp://127.0.0.1:" in str(error) and "runs gcs-planner 0.0.1-old" in str(
        error
    )
    assert "cells saved" in str(error) and "resume with --resume" in str(error)


def _worker_state() -> tuple[bool, bool, object, int]:
    """On a worker: planner imported, the compiled airplane legs loaded, SIGINT's handler, the
    parent process."""
    kernel = sys.modules.get("gcs_planner.geometry.airplane_kernel")
    return (
        "gcs_planner.core.planner" in sys.modules,
        kernel is not None and bool(kernel.airplane_lengths.signatures),
        signal.getsignal(signal.SIGINT),
        os.getppid(),
    )


def test_local_workers_are_forked_with_the_planner_imported_and_sigint_ignored() -> None:
    """The sweep's own cluster forks its workers from a forkserver that imported the planner
    (gcs_planner/sweep/worker_start.py): before any cell they hold it and the compiled airplane
    legs every cell flies (gcs_planner/sweep/warm.py), and ignore SIGINT."""
    from gcs_planner.sweep.worker_start import start_method

    assert start_method() == "forkserver"  # Linux
    # One worker: what each worker holds is the subject, not how many there are.
    client, cluster = runner._connect(None, 1, 1, "127.0.0.1:0")
    try:
        client.wait_for_workers(1, timeout=120)
        first = client.run(_worker_state)
        assert len(first) == 1, first
        # forked by the forkserver, not spawned by a nanny in this process
        for planner, legs, sigint, parent in first.values():
            assert planner and legs and sigint == signal.SIG_IGN, first
            assert parent != os.getpid(), first
        # a worker its nanny restarts is spawned, as Dask does, and ignores SIGINT alike
        client.restart(timeout=120)
        again = client.run(_worker_state)
        assert len(again) == 1 and all(s[0] and s[2] == signal.SIG_IGN for s in again.values())
    finally:
        runner._disconnect(client, cluster)
