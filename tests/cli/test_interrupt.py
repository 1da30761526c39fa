"""Ctrl-C at any moment of `gcs-planner plan`, its imports included (issues 28 and 54): one line
"interrupted", exit 130, no traceback.

Each case holds the process at the import of one module (``GCS_PLANNER_HOLD_IMPORT``,
gcs_planner/runtime/hold.py: the process says so on stderr and waits for a signal) and sends
SIGINT once it has read that line, so the signal lands where the case means it to, on a quiet
or a loaded machine: during the command line's own import, while the parser imports the
command, while the command imports the planner, and inside the plan (where Ctrl-C is a flag the
compiled search reads: the search kernel's module is imported, then the kernel runs with the
flag set)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from gcs_planner.runtime.hold import HELD, VARIABLE

ENTRY = Path(sys.executable).parent / "gcs-planner"
TABLE2 = ["--alpha1", "20", "--alpha2", "10", "--beta1", "15", "--beta2", "20", "--theta", "20",
          "--delta", "0.001", "--objectives", "length,corrections,probability",
          "--progress"]  # fmt: skip
# Generous: an interrupted plan ends within interrupt.GRACE (5 s) even on a slow machine.
WAIT = 300.0


def _default_sigint() -> None:
    # A child of a shell without job control inherits SIGINT ignored, and Python then keeps it
    # ignored: the test would see a plan that never heard the signal.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def interrupt_at(command: list[str], module: str, **env: str) -> tuple[int, str, str]:
    """Run ``command`` held at the import of ``module``, send SIGINT there; (status, out, err)."""
    proc = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, VARIABLE: module, **env},
        preexec_fn=_default_sigint,
    )
    assert proc.stderr is not None
    before = []  # progress lines may come first
    try:
        for line in proc.stderr:
            if line.strip() == f"{HELD} {module}":
                proc.send_signal(signal.SIGINT)
                break
            before.append(line)
        else:  # the process ended without importing the module
            proc.wait(timeout=WAIT)
            pytest.fail(f"never held at the import of {module}: {''.join(before)[-2000:]}")
        out, err = proc.communicate(timeout=WAIT)
    finally:
        if proc.poll() is None:  # a failed case leaves no held process behind
            proc.kill()
            proc.wait()
    return proc.returncode, out, "".join(before) + err


def _one_line_and_130(code: int, out: str, err: str) -> None:
    assert "Traceback" not in err, err
    assert code == 130, (code, err)
    assert err.rstrip().splitlines()[-1] == "gcs-planner: interrupted", err
    assert err.count("interrupted") == 1, err
    assert out == ""


@pytest.mark.parametrize(
    ("entry", "module"),
    [
        ("python -m", "gcs_planner.cli"),  # the command line's own first import
        ("script", "gcs_planner.cli"),  # the same, before the script's main() runs
        ("script", "gcs_planner.cli.plan"),  # the parser imports the command
        ("script", "gcs_planner.core.planner"),  # the command imports the planner
    ],
)
def test_ctrl_c_during_the_imports_ends_with_one_line_and_exit_130(
    dataset_paths: dict[int, Path], entry: str, module: str
) -> None:
    assert ENTRY.exists(), f"{ENTRY} missing: install the package (pip install -e .)"
    start = [sys.executable, "-m", "gcs_planner"] if entry == "python -m" else [str(ENTRY)]
    _one_line_and_130(*interrupt_at([*start, "plan", str(dataset_paths[2]), *TABLE2], module))


def test_ctrl_c_during_a_compiled_plan_ends_with_one_line_and_exit_130(
    dataset_paths: dict[int, Path],
) -> None:
    """Held as the plan imports the search kernel (GCS_PLANNER_COMPILE=always: the compiled
    search even on a fresh cache): the signal arrives inside the plan, the kernel runs with the
    flag set and stops at its first tick, or the watchdog ends a compile that outlasts it."""
    command = [str(ENTRY), "plan", str(dataset_paths[2]), *TABLE2]
    module = "gcs_planner.core.search_kernel"
    _one_line_and_130(*interrupt_at(command, module, GCS_PLANNER_COMPILE="always"))
