"""`gcs-planner sweep SPEC.toml --out DIR`: a study over scenarios and parameters on Dask."""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from gcs_planner.cli.common import add_quiet_argument
from gcs_planner.errors import InputError


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "sweep",
        help="plan many scenarios x parameter values as tasks on Dask (local or a cluster)",
        description="Run a sweep spec: every scenario with every set of values, each cell one "
        "plan (and optional dry run) on Dask. Writes DIR/results.parquet, results.csv and "
        "summary.png. Needs the sweep extra: pip install 'gcs-planner[sweep]'.",
    )
    p.add_argument("spec", help="sweep spec (.toml); see missions/sweep-example.toml")
    p.add_argument("--out", type=Path, required=True, help="folder for the results")
    where = p.add_mutually_exclusive_group()
    where.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="submit to this running Dask scheduler (tcp://HOST:8786) instead of starting a "
        "local cluster; the scenario files must be readable by its workers at the same paths "
        "(default: $DASK_SCHEDULER_ADDRESS when set)",
    )
    where.add_argument(
        "--scheduler-file",
        metavar="PATH",
        type=Path,
        help="the JSON file a scheduler wrote (dask scheduler --scheduler-file PATH, as batch "
        "jobs on a shared file system do): submit to the address it names",
    )
    p.add_argument(
        "--connect-timeout",
        type=float,
        metavar="SECONDS",
        help="how long to try reaching the scheduler (default 20, runner.CONNECT_TIMEOUT_S)",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=2,
        help="worker processes of the local cluster (default 2, one thread each)",
    )
    p.add_argument(
        "--resume", action="store_true", help="keep the finished cells in DIR, run the others"
    )
    p.add_argument(
        "--prune",
        action="store_true",
        help="with --resume: accept a changed spec, dropping the rows of cells no longer in it",
    )
    p.add_argument(
        "--retry-failed",
        action="store_true",
        help="with --resume: run the cells whose task failed (status error) again",
    )
    p.add_argument(
        "--no-workers-timeout",
        type=float,
        default=60.0,
        metavar="SECONDS",
        help="stop, the finished cells saved, once the scheduler has had no worker for this "
        "long (default 60; exit status 4)",
    )
    p.add_argument(
        "--min-workers",
        type=int,
        default=0,
        metavar="N",
        help="wait until the cluster has N workers before submitting (batch jobs take time to "
        "start); default: start at once",
    )
    p.add_argument(
        "--min-workers-timeout",
        type=float,
        default=600.0,
        metavar="SECONDS",
        help="how long --min-workers waits before it stops with a message (default 600; "
        "exit status 4)",
    )
    p.add_argument(
        "--dashboard-address",
        default="127.0.0.1:0",
        help="the local cluster's dashboard (default: a free port on 127.0.0.1, printed)",
    )
    add_quiet_argument(p)
    p.set_defaults(func=run)


def scheduler_address(given: str | None, scheduler_file: Path | None) -> tuple[str | None, str]:
    """The scheduler to submit to and where it came from: ``--scheduler``, the address in
    ``--scheduler-file``, or Dask's own DASK_SCHEDULER_ADDRESS (which a cluster's job scripts
    export); None: a local cluster."""
    if given is not None:
        return given, "--scheduler"
    if scheduler_file is not None:
        try:
            data = json.loads(scheduler_file.read_text(encoding="utf-8"))
        except OSError as exc:
            raise InputError(
                f"cannot read it: {exc.strerror or exc}", file=str(scheduler_file)
            ) from None
        except (ValueError, UnicodeDecodeError) as exc:
            raise InputError(
                f"is not a Dask scheduler file (not JSON: {exc})", file=str(scheduler_file)
            ) from None
        address = data.get("address") if isinstance(data, dict) else None
        if not isinstance(address, str) or not address.strip():
            raise InputError(
                "names no scheduler address (a scheduler writes one when it has started)",
                file=str(scheduler_file),
                field="address",
            )
        return address, f"--scheduler-file {scheduler_file}"
    env = os.environ.get("DASK_SCHEDULER_ADDRESS", "").strip()
    return env or None, "DASK_SCHEDULER_ADDRESS"


def run(args: argparse.Namespace) -> int:
    from gcs_planner.sweep import INSTALL_HINT, missing_dependencies

    missing = missing_dependencies()
    if missing:
        raise InputError(f"sweep needs {' and '.join(missing)}: {INSTALL_HINT}")
    if args.workers < 1:
        raise InputError(f"must be >= 1 (got {args.workers})", field="--workers")
    if args.scheduler is not None and not args.scheduler.strip():
        raise InputError("is empty: give the scheduler's address", field="--scheduler")
    if args.connect_timeout is not None and not args.connect_timeout > 0:
        raise InputError(f"must be > 0 (got {args.connect_timeout:g})", field="--connect-timeout")
    for flag in ("prune", "retry_failed"):
        if getattr(args, flag) and not args.resume:
            raise InputError("needs --resume", field="--" + flag.replace("_", "-"))
    if args.min_workers < 0:
        raise InputError(f"must be >= 0 (got {args.min_workers})", field="--min-workers")
    if not args.min_workers_timeout > 0:
        raise InputError(
            f"must be > 0 (got {args.min_workers_timeout:g})", field="--min-workers-timeout"
        )
    if not args.no_workers_timeout > 0:
        raise InputError(
            f"must be > 0 (got {args.no_workers_timeout:g})", field="--no-workers-timeout"
        )

    from gcs_planner.runtime.interrupt import EXIT_CODE
    from gcs_planner.sweep import read_spec, run_sweep
    from gcs_planner.sweep.runner import SweepInterrupted

    spec = read_spec(args.spec)
    if spec.cluster is not None and args.scheduler is None and args.scheduler_file is None:
        # the spec's [cluster] starts its own scheduler; DASK_SCHEDULER_ADDRESS is not asked
        from gcs_planner.sweep.jobqueue import require_jobqueue

        require_jobqueue(spec.path)
        scheduler, scheduler_from = None, "[cluster]"
    else:
        scheduler, scheduler_from = scheduler_address(args.scheduler, args.scheduler_file)
    try:
        result = run_sweep(
            spec,
            args.out,
            scheduler=scheduler,
            scheduler_from=scheduler_from,
            workers=args.workers,
            resume=args.resume,
            dashboard_address=args.dashboard_address,
            stream=sys.stdout,
            quiet=args.quiet,
            no_workers_timeout=args.no_workers_timeout,
            prune=args.prune,
            retry_failed=args.retry_failed,
            min_workers=args.min_workers,
            min_workers_timeout=args.min_workers_timeout,
            **({} if args.connect_timeout is None else {"connect_timeout": args.connect_timeout}),
        )
    except SweepInterrupted as exc:
        # the table is saved: say how much, and how to go on
        print(f"gcs-planner: {exc}", file=sys.stderr)
        return EXIT_CODE
    print(
        f"{result.ran} cells run ({result.failed} failed, {result.infeasible} infeasible), "
        f"{result.skipped} already done, in {result.seconds:.1f} s"
    )
    print(f"wrote {', '.join(str(p) for p in result.files)}")
    return 0
