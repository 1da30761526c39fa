"""The command line: a thin layer that parses, calls the library and prints.

Each subcommand is a module in this package with ``add_parser(subparsers)`` (which sets
``func``); errors the user can act on are :class:`~gcs_planner.errors.GcsPlannerError` and
become one line on stderr and the error's exit code, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from gcs_planner import __version__
from gcs_planner.errors import GcsPlannerError

# Subcommand modules, in the order `--help` lists them.
COMMANDS = ("plan", "export", "upload", "download", "mock_vehicle", "dry_run", "sweep")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="gcs-planner",
        description="Mission planner for INS-only maritime fixed-wing UAVs.",
    )
    parser.add_argument("--version", action="version", version=f"gcs-planner {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        importlib.import_module(f"gcs_planner.cli.{name}").add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except GcsPlannerError as exc:
        print(f"gcs-planner: error: {exc}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("gcs-planner: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
