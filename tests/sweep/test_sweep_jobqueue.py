"""The spec's [cluster]: workers started as batch jobs through dask-jobqueue, end to end.

There is no SLURM here, so the test puts stand-in ``sbatch``, ``squeue`` and ``scancel``
scripts on PATH: ``sbatch`` keeps a copy of the job script dask-jobqueue wrote and starts it as
a local process (its own session, as a job is), ``scancel`` ends that process group, ``squeue``
lists the jobs still running. Everything else is real: dask-jobqueue's scheduler in the sweep's
process, the `dask worker` processes its job scripts start, on 127.0.0.1.

dask-jobqueue is the ``cluster`` extra, installed by the ``test`` extra: without it these tests
fail saying so, rather than skip.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from support.paths import MISSIONS

from gcs_planner.errors import InputError
from gcs_planner.sweep import read_results, read_spec

EXAMPLE_SCENARIO = MISSIONS / "example" / "scenario.toml"
BIN = Path(sys.executable).parent
DEADLINE_S = 300.0

SBATCH = """#!/usr/bin/env bash
# stand-in sbatch: start the job script as a local process in its own session
set -e
jobs="{jobs}"
id=$$
cp "$1" "$jobs/$id.sh"
setsid bash "$jobs/$id.sh" > "$jobs/$id.out" 2>&1 < /dev/null &
echo $! > "$jobs/$id.pid"
echo "Submitted batch job $id"
"""
SCANCEL = """#!/usr/bin/env bash
# stand-in scancel: end the job's process group
jobs="{jobs}"
for id in "$@"; do
  echo "$id" >> "$jobs/cancelled"
  kill -TERM -- "-$(cat "$jobs/$id.pid")" 2>/dev/null || true
done
"""
SQUEUE = """#!/usr/bin/env bash
# stand-in squeue: the jobs whose process still runs
jobs="{jobs}"
echo "JOBID STATE"
for pid in "$jobs"/*.pid; do
  [ -e "$pid" ] || continue
  id=$(basename "$pid" .pid)
  kill -0 "$(cat "$pid")" 2>/dev/null && echo "$id R"
done
exit 0
"""


def require_jobqueue() -> None:
    try:
        import dask_jobqueue  # noqa: F401
    except ImportError:
        pytest.fail(
            "dask-jobqueue is not installed: pip install '.[cluster]' (the test extra installs "
            "it too; .ci/run installs '.[test]')"
        )


@pytest.fixture
def slurm(tmp_path: Path) -> Path:
    """A folder of stand-in SLURM commands; the jobs' files in tmp_path/jobs."""
    require_jobqueue()
    bin_dir, jobs = tmp_path / "bin", tmp_path / "jobs"
    bin_dir.mkdir()
    jobs.mkdir()
    for name, text in (("sbatch", SBATCH), ("scancel", SCANCEL), ("squeue", SQUEUE)):
        path = bin_dir / name
        path.write_text(text.format(jobs=jobs))
        path.chmod(0o755)
    yield jobs
    for pid_file in jobs.glob("*.pid"):  # a hang guard's leftovers: no job outlives the test
        try:
            os.killpg(int(pid_file.read_text()), signal.SIGKILL)
        except (ProcessLookupError, PermissionError, ValueError):
            pass


def write_spec(tmp_path: Path, cluster: str) -> Path:
    path = tmp_path / "spec.toml"
    path.write_text(
        f"""
[[scenarios]]
file = "{EXAMPLE_SCENARIO}"
[[scenarios]]
generate = "random"
corrections = 24
seeds = [1, 2]
box = [40000, 20000, 2000]
[grid]
delta = [0.001, 0.0011]
[plan]
objectives = ["length", "corrections"]
[cluster]
{cluster}
""",
        encoding="utf-8",
    )
    return path


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def wait_for(condition, what: str) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"gave up waiting for {what}")
        time.sleep(0.1)


def test_cluster_section_runs_the_sweep_on_slurm_jobs(tmp_path: Path, slurm: Path) -> None:
    spec_path = write_spec(
        tmp_path,
        'system = "slurm"\njobs = 2\ncores = 1\nmemory = "1GB"\nwalltime = "00:10:00"\n'
        'queue = "debug"\nhost = "127.0.0.1"\n',
    )
    env = {**os.environ, "PATH": f"{tmp_path / 'bin'}{os.pathsep}{os.environ['PATH']}"}
    # a scheduler address in the environment is not asked: the [cluster] starts its own
    env["DASK_SCHEDULER_ADDRESS"] = "tcp://127.0.0.1:9"
    done = subprocess.run(
        [str(BIN / "gcs-planner"), "sweep", str(spec_path), "--out", str(tmp_path / "out"),
         "--min-workers", "2", "--min-workers-timeout", str(DEADLINE_S)],
        capture_output=True, text=True, timeout=DEADLINE_S, env=env,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr + "".join(p.read_text() for p in slurm.glob("*.out"))
    assert "running on 2 SLURM jobs of 1 core, 1GB (queue debug, walltime 00:10:00)" in (
        done.stdout
    )
    assert "6 cells run (0 failed, 0 infeasible)" in done.stdout
    # two jobs submitted, with the spec's resources in the scripts dask-jobqueue wrote
    scripts = sorted(slurm.glob("*.sh"))
    assert len(scripts) == 2
    for script in scripts:
        text = script.read_text()
        assert "#SBATCH -p debug" in text and "#SBATCH -t 00:10:00" in text
        assert "#SBATCH --cpus-per-task=1" in text and "#SBATCH --mem=" in text
        # the jobs run the sweep's own Python (this installation, seen by every node)
        assert f"{BIN}/python" in text
        assert " -m distributed.cli.dask_worker tcp://127.0.0.1:" in text
    # the cells ran in the jobs' worker processes, not here
    rows = read_results(tmp_path / "out")
    assert len({r["cell_key"] for r in rows}) == 6 and all(r["status"] == "ok" for r in rows)
    workers = {int(r["worker"].rsplit(":", 1)[1]) for r in rows}
    assert os.getpid() not in workers and done.returncode == 0
    # and at the end every job was cancelled and its processes are gone
    ids = sorted(p.stem for p in scripts)
    assert sorted((slurm / "cancelled").read_text().split()) == ids
    pids = [int((slurm / f"{i}.pid").read_text()) for i in ids]
    wait_for(lambda: not any(alive(p) for p in [*pids, *workers]), "the jobs to end")
    squeue = subprocess.run([str(tmp_path / "bin" / "squeue")], capture_output=True, text=True)
    assert squeue.stdout.split() == ["JOBID", "STATE"]


@pytest.mark.parametrize(
    "system, lines",
    [
        ("pbs", ["#PBS -q batch", "#PBS -l walltime=01:00:00", "#PBS -l select=1:ncpus=4"]),
        ("sge", ["#$ -q batch", "#$ -l h_rt=01:00:00"]),
    ],
)
def test_pbs_and_sge_job_scripts_carry_the_spec_s_resources(
    tmp_path: Path, system: str, lines: list[str]
) -> None:
    require_jobqueue()
    from gcs_planner.sweep.jobqueue import job_cluster

    spec = read_spec(
        write_spec(
            tmp_path,
            f'system = "{system}"\njobs = 3\ncores = 4\nprocesses = 2\nmemory = "8GB"\n'
            'walltime = "01:00:00"\nqueue = "batch"\nhost = "127.0.0.1"\n'
            'job_directives = ["-V"]\n',
        )
    )
    assert spec.cluster is not None and spec.cluster.jobs == 3
    cluster = job_cluster(spec.cluster)  # no job is submitted until it is scaled
    try:
        script = cluster.job_script()
    finally:
        cluster.close()
    for line in lines:
        assert line in script, script
    assert "--nworkers 2" in script and "--nthreads 2" in script and " -V" in script


@pytest.mark.parametrize(
    "cluster, said",
    [
        ('system = "lsf"\ncores = 1\nmemory = "1GB"', "field 'cluster.system': unknown batch"),
        ('system = "slurm"\nmemory = "1GB"', "field 'cluster.cores': missing key"),
        ('system = "slurm"\ncores = 1\nmemory = "lots"', "field 'cluster.memory': must be an"),
        (
            'system = "slurm"\ncores = 4\nprocesses = 3\nmemory = "1GB"',
            "field 'cluster.processes': must divide cores",
        ),
        (
            'system = "slurm"\ncores = 1\nmemory = "1GB"\nwalltime = "ten minutes"',
            "field 'cluster.walltime'",
        ),
        ('system = "sge"\ncores = 1\nmemory = "1GB"\naccount = "x"', "SGE jobs take no account"),
        ('system = "slurm"\ncores = 1\nmemory = "1GB"\nnodes = 2', "unknown key 'nodes'"),
    ],
)
def test_bad_cluster_section_names_the_field(tmp_path: Path, cluster: str, said: str) -> None:
    path = write_spec(tmp_path, cluster)
    with pytest.raises(InputError) as error:
        read_spec(path)
    assert str(path) in str(error.value) and "row " in str(error.value)
    assert said in str(error.value)


def test_cluster_without_the_batch_system_s_commands_is_one_line(tmp_path: Path) -> None:
    require_jobqueue()
    spec_path = write_spec(tmp_path, 'system = "slurm"\ncores = 1\nmemory = "1GB"\n')
    empty = tmp_path / "empty-bin"
    empty.mkdir()
    done = subprocess.run(
        [sys.executable, "-m", "gcs_planner", "sweep", str(spec_path),
         "--out", str(tmp_path / "out")],
        capture_output=True, text=True, timeout=DEADLINE_S,
        env={**os.environ, "PATH": str(empty)},
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    assert "field 'cluster.system'" in done.stderr and "'sbatch', which is not on PATH" in (
        done.stderr
    )
