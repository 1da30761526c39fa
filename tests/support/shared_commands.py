"""Documented shell commands run once per test run, shared by the test processes that need them.

Several tests run the same documented command: README's first command writes `out/coast`, which
six other commands read, and two documents show the same sweep and benchmark lines. Each xdist
worker would run each of them again in a workspace of its own. Here the first process to need a
command runs it (a real subprocess, as written), keeps its exit code, output and the `out/...`
folders it wrote in the run's folder (tests/conftest.py's GCS_PLANNER_TEST_RESULTS, removed at
the run's end), and every later process waits for it and copies them into its own workspace.
Outside a run's folder (GCS_PLANNER_TEST_RESULTS unset) every command simply runs."""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path

from support.shared_results import _sources_digest


def _store(command: str) -> Path | None:
    where = os.environ.get("GCS_PLANNER_TEST_RESULTS")
    if not where:
        return None
    key = hashlib.sha256(f"{_sources_digest()}|{command}".encode()).hexdigest()
    return Path(where) / "commands" / key[:32]


def run_once(
    command: str,
    cwd: Path,
    writes: set[str],
    run: Callable[[], subprocess.CompletedProcess],
) -> subprocess.CompletedProcess:
    """``run()``'s result for ``command`` (its text as documented), run in ``cwd`` by the first
    process of this run that asks and copied from it by every other: the exit code, stdout,
    stderr and the folders ``out/<name>`` of ``writes`` (into ``cwd / "out"``). A lock per
    command makes a second process wait for the first rather than run it beside it."""
    store = _store(command)
    if store is None:
        return run()
    store.parent.mkdir(parents=True, exist_ok=True)
    with open(store.with_suffix(".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes, also on an error
        done = store / "done.json"
        if not done.exists():
            result = run()
            _keep(store, cwd, writes, result)
        kept = json.loads(done.read_text(encoding="utf-8"))
    for name in sorted(writes):
        source, target = store / "out" / name, cwd / "out" / name
        if source.exists() and not target.exists():
            target.parent.mkdir(parents=True, exist_ok=True)
            copy = shutil.copytree if source.is_dir() else shutil.copy2
            copy(source, target)
    return subprocess.CompletedProcess(command, kept["returncode"], kept["stdout"], kept["stderr"])


def _keep(store: Path, cwd: Path, writes: set[str], result: subprocess.CompletedProcess) -> None:
    """The result and the written folders, whole or not at all (renamed into place last)."""
    partial = Path(tempfile.mkdtemp(dir=store.parent, suffix=".tmp"))
    for name in sorted(writes):
        source = cwd / "out" / name
        if source.exists():
            target = partial / "out" / name
            target.parent.mkdir(parents=True, exist_ok=True)
            copy = shutil.copytree if source.is_dir() else shutil.copy2
            copy(source, target, **({"symlinks": True} if source.is_dir() else {}))
    kept = {"returncode": result.returncode, "stdout": result.stdout, "stderr": result.stderr}
    (partial / "done.json").write_text(json.dumps(kept), encoding="utf-8")
    os.replace(partial, store)
