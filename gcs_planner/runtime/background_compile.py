"""Compile the kernels the commands use once, without being asked: in a detached background
process started as a plan or dry run that ran without some of them ends.

A user who never runs ``gcs-planner compile`` planned in Python at every run, several times
slower than with the cached kernels (issue 54). So when a command that
plans ends with a kernel of :data:`gcs_planner.runtime.precompile.KERNELS` not in numba's cache,
it starts ``python -m gcs_planner.runtime.background_compile``: a process of its own session,
at the lowest priority (``nice`` 19), its input and output the null device (it never writes into
the user's terminal, during the command or after), compiling the kernels one at a time as
``gcs-planner compile`` does, under a lock file so that two never race. The command does not
wait for it; the next plans find the kernels cached.

Off with ``GCS_PLANNER_BACKGROUND_COMPILE=0``, and under pytest (``PYTEST_CURRENT_TEST``, which a
test's subprocesses inherit) unless the variable says ``1``: tests compile what they mean to.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import subprocess
import sys
from pathlib import Path

VARIABLE = "GCS_PLANNER_BACKGROUND_COMPILE"
NICENESS = 19
_armed = False


def enabled() -> bool:
    """Whether a command may start the background compile (see the module's doc)."""
    value = os.environ.get(VARIABLE, "").strip().lower()
    if value in ("0", "off", "no", "false"):
        return False
    if value in ("1", "on", "yes", "true"):
        return True
    return "PYTEST_CURRENT_TEST" not in os.environ


def lock_path() -> Path:
    """The lock file beside the numba cache it fills (the user's NUMBA_CACHE_DIR, else the
    user-wide cache folder)."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"]) / "gcs-planner-compile.lock"
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    return cache / "gcs-planner" / "compile.lock"


def _busy(lock: Path) -> bool:
    """Whether a background compile holds ``lock`` now."""
    import fcntl

    try:
        with lock.open("a") as f:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            fcntl.flock(f, fcntl.LOCK_UN)
    except BlockingIOError:
        return True
    except OSError:
        return False
    return False


def needed() -> bool:
    """Whether a kernel the commands use is not in numba's cache (read without numba)."""
    from gcs_planner.runtime.precompile import missing

    return bool(missing())


def start() -> bool:
    """Start the background compile, detached, unless it is off, nothing is missing or one
    runs already; whether one was started."""
    if not enabled() or not hasattr(os, "nice") or not needed():
        return False
    lock = lock_path()
    with contextlib.suppress(OSError):
        lock.parent.mkdir(parents=True, exist_ok=True)
    if _busy(lock):
        return False
    env = {**os.environ, VARIABLE: "0"}  # its own dry run starts no other
    try:
        subprocess.Popen(
            [sys.executable, "-m", "gcs_planner.runtime.background_compile"],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            env=env,
            start_new_session=True,  # a Ctrl-C in the user's terminal is not its
            close_fds=True,
        )
    except OSError:
        return False
    return True


def after_this_command() -> bool:
    """Arrange :func:`start` for when this process exits (its output written), once; whether
    it will run. The caller says, before then, that kernels are being compiled."""
    global _armed
    if _armed:
        return True
    if not enabled() or not needed():
        return False
    _armed = True
    atexit.register(start)
    return True


def main() -> int:
    """The background process: lowest priority, the lock, every kernel compiled in turn."""
    import fcntl

    os.nice(NICENESS)
    lock = lock_path()
    lock.parent.mkdir(parents=True, exist_ok=True)
    with lock.open("a") as f:
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return 0  # another compiles them
        from gcs_planner.runtime.precompile import compile_kernels, missing

        if missing():
            compile_kernels(say=lambda text: None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
