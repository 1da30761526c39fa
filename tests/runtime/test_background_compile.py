"""The kernels compiled once without being asked (issue 54; gcs_planner/runtime/
background_compile.py): off under pytest and by the variable, detached and silent when it
starts, never two at once (the lock)."""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from gcs_planner.runtime import background_compile as bg


def test_on_by_default_off_under_pytest_and_by_the_variable(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv(bg.VARIABLE, raising=False)
    assert "PYTEST_CURRENT_TEST" in os.environ and not bg.enabled()
    monkeypatch.delenv("PYTEST_CURRENT_TEST")
    assert bg.enabled()
    for off in ("0", "off", "no"):
        monkeypatch.setenv(bg.VARIABLE, off)
        assert not bg.enabled()
    monkeypatch.setenv("PYTEST_CURRENT_TEST", "x")
    monkeypatch.setenv(bg.VARIABLE, "1")
    assert bg.enabled()


def _uncached(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    monkeypatch.setenv(bg.VARIABLE, "1")
    assert bg.needed()  # an empty cache: every kernel is missing


def _record_starts(monkeypatch: pytest.MonkeyPatch, popen: object) -> None:
    """The module's subprocess.Popen replaced (only the module's: the test runs its own)."""
    fake = SimpleNamespace(Popen=popen, DEVNULL=subprocess.DEVNULL)
    monkeypatch.setattr(bg, "subprocess", fake)


def test_it_starts_detached_silent_and_without_starting_another(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    _uncached(monkeypatch, tmp_path)
    started: list[tuple[list[str], dict]] = []
    _record_starts(monkeypatch, lambda args, **kw: started.append((args, kw)))
    assert bg.start()
    ((args, kw),) = started
    assert args == [sys.executable, "-m", "gcs_planner.runtime.background_compile"]
    assert kw["start_new_session"]  # the user's Ctrl-C is not its
    for stream in ("stdin", "stdout", "stderr"):
        assert kw[stream] is subprocess.DEVNULL  # never a word in the user's terminal
    assert kw["env"][bg.VARIABLE] == "0"
    assert kw["env"]["NUMBA_CACHE_DIR"] == str(tmp_path / "numba")


def test_none_starts_while_one_holds_the_lock(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    _uncached(monkeypatch, tmp_path)
    started: list[object] = []
    _record_starts(monkeypatch, lambda *a, **kw: started.append(a))
    lock = bg.lock_path()
    lock.parent.mkdir(parents=True, exist_ok=True)
    with lock.open("a") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        assert not bg.start()
        # The background process itself, started while the lock is held, leaves at once and
        # compiles nothing (no index file in its cache).
        done = subprocess.run(
            [sys.executable, "-m", "gcs_planner.runtime.background_compile"],
            env={**os.environ},
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode == 0, done.stderr
        assert list((tmp_path / "numba").rglob("*.nbi")) == []
    assert started == []
    monkeypatch.setenv(bg.VARIABLE, "0")
    assert not bg.start() and not bg.after_this_command()
