"""Reference fronts shared across the test processes of a run (xdist's workers each ask for
the same brute-force fronts): kept on disk under a key of the question and of every source
file that can change the answer (the package, the simulator, tests/support) and the Python and
numpy versions, so that a changed source computes the front again, never reuses an old one."""

from __future__ import annotations

import functools
import hashlib
import json
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

_ROOT = Path(__file__).resolve().parents[2]
_SOURCES = ("gcs_planner", "sim", "tests/support")


@functools.cache
def _sources_digest() -> str:
    """One digest of every Python source the answers depend on, and the versions."""
    digest = hashlib.sha256(f"{sys.version}|{np.__version__}".encode())
    for folder in _SOURCES:
        for path in sorted((_ROOT / folder).rglob("*.py")):
            digest.update(str(path.relative_to(_ROOT)).encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def _folder() -> Path:
    where = os.environ.get("GCS_PLANNER_TEST_RESULTS")
    return Path(where) if where else Path(tempfile.gettempdir()) / "gcs-planner-test-results"


def shared_front(
    name: str, question: tuple, compute: Callable[[], list[tuple]]
) -> list[tuple[float, int, float]]:
    """``compute()``'s front of (length, corrections, -probability) tuples, read from the disk
    when another process of this run made it (tests/conftest.py gives each run a folder); written
    whole or not at all (a temporary file renamed), so a process never reads half a front."""
    key = hashlib.sha256(f"{_sources_digest()}|{name}|{question!r}".encode()).hexdigest()
    path = _folder() / f"{name}-{key[:32]}.json"
    try:
        return [(float(a), int(b), float(c)) for a, b, c in json.loads(path.read_text())]
    except (OSError, ValueError):
        pass
    front = compute()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        with os.fdopen(fd, "w") as out:
            json.dump([[float(a), int(b), float(c)] for a, b, c in front], out)
        os.replace(tmp, path)
    except OSError:
        pass  # a read-only or full disk: the front is still right, only not shared
    return front
