"""`gcs-planner compile`: compile the planner's and the dry run's numba kernels now, once, rather
than at the first plan that needs them (gcs_planner/runtime/precompile.py)."""

from __future__ import annotations

import argparse
import sys


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "compile",
        help="compile the planner's kernels once (numba), so that every later plan is fast",
        description="Compile the search kernels and the dry run's flight kernels into numba's "
        "cache. Until they are compiled, plans that Python proves quickly run in Python and the "
        "first plan compiles them in a background process when it ends "
        "(GCS_PLANNER_BACKGROUND_COMPILE=0 turns that off); the others compile them at once.",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from gcs_planner.runtime.precompile import compile_kernels, missing

    before = missing()
    print("not compiled yet: " + (", ".join(before) if before else "none (all cached)"))
    for name, seconds in compile_kernels(lambda text: print(text, file=sys.stderr)):
        print(f"{name}: {seconds:.1f} s")
    after = missing()
    if after:
        print("still not in numba's cache: " + ", ".join(after), file=sys.stderr)
        return 1
    print("every kernel is in numba's cache")
    return 0
