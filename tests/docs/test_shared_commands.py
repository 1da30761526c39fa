"""A documented command shared across the test processes of a run runs once, and every later
caller gets its exit code, output and `out/...` folders (tests/support/shared_commands.py)."""

from __future__ import annotations

import subprocess
from pathlib import Path

from support.shared_commands import run_once


def writer(cwd: Path, calls: list[Path]):
    def run() -> subprocess.CompletedProcess:
        calls.append(cwd)
        (cwd / "out" / "made").mkdir(parents=True)
        (cwd / "out" / "made" / "plan.json").write_text("{}", encoding="utf-8")
        return subprocess.CompletedProcess("x", 3, "said", "warned")

    return run


def test_a_command_runs_once_and_its_outputs_reach_every_workspace(tmp_path, monkeypatch):
    monkeypatch.setenv("GCS_PLANNER_TEST_RESULTS", str(tmp_path / "run"))
    first, second = tmp_path / "first", tmp_path / "second"
    first.mkdir()
    second.mkdir()
    calls: list[Path] = []
    a = run_once("gcs-planner plan x --out out/made", first, {"made"}, writer(first, calls))
    b = run_once("gcs-planner plan x --out out/made", second, {"made"}, writer(second, calls))
    assert calls == [first]
    for done in (a, b):
        assert (done.returncode, done.stdout, done.stderr) == (3, "said", "warned")
    assert (second / "out" / "made" / "plan.json").read_text(encoding="utf-8") == "{}"
    # Another command is another entry: it runs.
    third = tmp_path / "third"
    run_once("gcs-planner plan y --out out/made", third, {"made"}, writer(third, calls))
    assert calls == [first, third]


def test_without_a_runs_folder_every_call_runs(tmp_path, monkeypatch):
    monkeypatch.delenv("GCS_PLANNER_TEST_RESULTS", raising=False)
    calls: list[Path] = []
    for name in ("first", "second"):
        cwd = tmp_path / name
        cwd.mkdir()
        run_once("gcs-planner plan x --out out/made", cwd, {"made"}, writer(cwd, calls))
    assert calls == [tmp_path / "first", tmp_path / "second"]
