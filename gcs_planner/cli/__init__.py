"""The command line: a thin layer that parses, calls the library and prints.

Each subcommand is a module in this package with ``add_parser(subparsers)`` (which sets
``func``); errors the user can act on are :class:`~gcs_planner.errors.GcsPlannerError` and
become one line on stderr and the error's exit code, never a traceback.

Only the module of the command being run is imported: the link's modules pull in pymavlink and
the planner's numpy and scipy, and a user who asks for ``--help`` or plans a scenario should not
wait for the others. The other commands appear in ``--help`` by their one-line summary.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from gcs_planner import __version__
from gcs_planner.errors import GcsPlannerError

# Subcommand modules, in the order `--help` lists them.
COMMANDS = (
    "plan", "export", "upload", "download", "fly", "mock_vehicle", "dry_run", "sweep",
    "compile",
)  # fmt: skip
# What `--help` says of a command whose module is not imported. A command missing here is
# imported whenever the parser is built (slower start, nothing else lost).
SUMMARIES = {
    "plan": "plan a scenario: the exact Pareto front and one chosen route",
    "export": "convert a plan JSON to a mission file, a map file or a picture",
    "upload": "upload a mission to a vehicle, read it back and compare",
    "download": "download the vehicle's mission to a file",
    "fly": "fly a contingency policy: upload, watch the corrections, switch missions in flight",
    "mock_vehicle": "run a simulated fixed-wing autopilot for a ground station to talk to",
    "dry_run": "plan, upload to a mock vehicle over loopback, read back, replay and report",
    "sweep": "plan many scenarios x parameter values as tasks on Dask (local or a cluster)",
    "compile": "compile the planner's kernels once (numba), so that every later plan is fast",
}


def command_name(module: str) -> str:
    return module.replace("_", "-")


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The parser; with ``argv``, only the command it names is built in full (None: all)."""
    parser = argparse.ArgumentParser(
        prog="gcs-planner",
        description="Mission planner for INS-only maritime fixed-wing UAVs.",
    )
    parser.add_argument("--version", action="version", version=f"gcs-planner {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    wanted = None if argv is None else _command_in(argv)
    for module in COMMANDS:
        if argv is None or module == wanted or module not in SUMMARIES:
            importlib.import_module(f"gcs_planner.cli.{module}").add_parser(sub)
        else:
            sub.add_parser(command_name(module), help=SUMMARIES[module])
    return parser


def _command_in(argv: Sequence[str]) -> str | None:
    """The module of the first argument that names a command (None when there is none)."""
    by_name = {command_name(m): m for m in COMMANDS}
    return next((by_name[a] for a in argv if a in by_name), None)


def main(argv: Sequence[str] | None = None) -> int:
    if argv is None:
        argv = sys.argv[1:]
    try:
        # Building the parser imports the command's module (numpy, scipy and the rest): a
        # Ctrl-C there is the user's as much as one during the plan.
        parser = build_parser(argv)
        args = parser.parse_args(argv)
        return int(args.func(args) or 0)
    except GcsPlannerError as exc:
        print(f"gcs-planner: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        return _interrupted()
    except SystemError as exc:
        # A Ctrl-C that still reached numba's C code (a kernel's boundary) surfaces as a
        # SystemError caused by the KeyboardInterrupt: the user pressed Ctrl-C, nothing failed.
        if not _caused_by_interrupt(exc):
            raise
        return _interrupted()
    except BrokenPipeError:
        return 0


def _interrupted() -> int:
    from gcs_planner.runtime.interrupt import EXIT_CODE, MESSAGE

    print(MESSAGE, file=sys.stderr)
    return EXIT_CODE


def _caused_by_interrupt(exc: BaseException) -> bool:
    """Whether a KeyboardInterrupt is in ``exc``'s chain of causes and contexts."""
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False
