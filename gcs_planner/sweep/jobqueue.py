"""Workers as batch jobs: the spec's [cluster] started through dask-jobqueue.

dask-jobqueue runs the scheduler in this process and submits job scripts (``sbatch``, ``qsub``)
that each start ``dask worker`` processes pointed at it; closing the cluster cancels the jobs
(``scancel``, ``qdel``). Every worker runs with one thread (``processes`` = ``cores`` by
default), as the local cluster's do: a cell is single-threaded Python and numba. The jobs run
this process's Python (``sys.executable``), so the cluster's nodes must see this installation
at the same path, as they must see the scenario files.

Needs the ``cluster`` extra (``pip install 'gcs-planner[cluster]'``).
"""

from __future__ import annotations

import contextlib
import importlib.util
import shutil
import sys

from gcs_planner.errors import InputError
from gcs_planner.sweep.spec import ClusterSpec

INSTALL_HINT = "pip install 'gcs-planner[cluster]' (from a checkout: pip install '.[cluster]')"
CLUSTER_CLASSES = {"slurm": "SLURMCluster", "pbs": "PBSCluster", "sge": "SGECluster"}
# What each batch system is called in messages.
SYSTEM_NAMES = {"slurm": "SLURM", "pbs": "PBS", "sge": "SGE"}


def require_jobqueue(spec_path: str) -> None:
    """Refuse a [cluster] section when dask-jobqueue is not installed, saying how to get it."""
    if importlib.util.find_spec("dask_jobqueue") is None:
        raise InputError(
            f"the [cluster] section needs dask-jobqueue: {INSTALL_HINT}",
            file=spec_path,
            field="cluster",
        )


def job_cluster(spec: ClusterSpec, dashboard_address: str = ":0"):
    """The dask-jobqueue cluster of ``spec``, not yet scaled (no job submitted)."""
    import dask_jobqueue

    cls = getattr(dask_jobqueue, CLUSTER_CLASSES[spec.system])
    options: dict = {
        "cores": spec.cores,
        "processes": spec.processes,
        "memory": spec.memory,
        "walltime": spec.walltime,
        "queue": spec.queue,
        "python": sys.executable,
        "job_name": "gcs-sweep",
        "log_directory": spec.log_directory,
        "job_extra_directives": list(spec.job_directives),
        "scheduler_options": {
            "dashboard_address": dashboard_address,
            **({"host": spec.host} if spec.host else {}),
        },
    }
    if spec.account is not None:
        options["account"] = spec.account
    return cls(**options)


def start_jobs(spec: ClusterSpec, spec_path: str, dashboard_address: str = ":0"):
    """Start ``spec``'s cluster and submit its jobs; returns the cluster (close it to cancel).

    dask-jobqueue submits in the background and only logs a failure: a batch system whose
    submit command is not on PATH is refused here, before anything starts."""
    import dask_jobqueue

    cls = getattr(dask_jobqueue, CLUSTER_CLASSES[spec.system])
    command = cls.job_cls.submit_command.split()[0]
    if shutil.which(command) is None:
        raise InputError(
            f"{SYSTEM_NAMES[spec.system]} jobs are submitted with {command!r}, which is not on "
            "PATH: run the sweep where jobs can be submitted (a login node)",
            file=spec_path,
            field="cluster.system",
        )
    cluster = job_cluster(spec, dashboard_address)
    try:
        cluster.scale(jobs=spec.jobs)
    except BaseException:
        close(cluster)
        raise
    return cluster


def close(cluster) -> None:
    """Close a job cluster, cancelling its jobs; a cluster whose jobs never started closes
    with an internal assertion in dask, which is no news to the user."""
    with contextlib.suppress(AssertionError):
        cluster.close()


def describe(spec: ClusterSpec) -> str:
    """The cluster in a line: "2 SLURM jobs of 2 cores, 4GB (queue debug)"."""
    jobs = f"{spec.jobs} {SYSTEM_NAMES[spec.system]} job{'s' if spec.jobs != 1 else ''}"
    where = f"{jobs} of {spec.cores} core{'s' if spec.cores != 1 else ''}, {spec.memory}"
    extra = [f"queue {spec.queue}"] if spec.queue else []
    if spec.walltime:
        extra.append(f"walltime {spec.walltime}")
    return where + (f" ({', '.join(extra)})" if extra else "")
