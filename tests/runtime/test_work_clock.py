"""The clock of a plan's time limit (gcs_planner.runtime.work_clock) counts the CPU the process
spends, less numba's compiling: the first plan after an install must not spend its limit on
compiling kernels it compiles once, and a busy machine (the process waiting for a core) must
not spend it either (issue 54)."""

from __future__ import annotations

import time

from numba.core import event

from gcs_planner.core.budget import Budget
from gcs_planner.runtime import work_clock


def _spin(cpu_seconds: float) -> None:
    """Work: this many seconds of the process's CPU, however long they take on the wall."""
    start = time.process_time()
    while time.process_time() - start < cpu_seconds:
        pass


def _compile(cpu_seconds: float, nested: bool = False) -> None:
    """A compile event of ``cpu_seconds`` of work as numba fires them (nested: a callee)."""
    with event.trigger_event("numba:compile", data={"dispatcher": None, "args": ()}):
        if nested:
            with event.trigger_event("numba:compile", data={"dispatcher": None, "args": ()}):
                _spin(cpu_seconds)
        else:
            _spin(cpu_seconds)


def test_the_clock_stops_while_numba_compiles() -> None:
    compiled0 = work_clock.compiling_seconds()
    cpu0 = time.process_time()
    work0 = work_clock.now()  # read after cpu0 ...
    _compile(0.2)
    _compile(0.1, nested=True)  # counted once, not twice
    work = work_clock.now() - work0  # ... and before cpu's end: work <= cpu - compiled
    cpu = time.process_time() - cpu0
    compiled = work_clock.compiling_seconds() - compiled0
    # The compiles took at least their work (the nested one once: twice would be >= 0.4 s
    # only if the process spent 0.1 s of CPU outside them), and the clock advanced by at most
    # the CPU spent less what they took.
    assert 0.3 <= compiled <= cpu
    assert work <= cpu - compiled + 1e-9


def test_waiting_is_not_work() -> None:
    """A process that waits (for a core on a busy machine, here for a sleep) spends no budget."""
    before = work_clock.now()
    time.sleep(0.3)
    assert work_clock.now() - before < 0.1  # a sleep's CPU, far below its 0.3 s of wall


def test_a_budget_spends_work_and_not_compiles_or_waiting() -> None:
    budget = Budget(time_limit=0.5)
    _compile(0.8)
    assert not budget.expired()  # 0.8 s of compile, and the limit is 0.5 s
    time.sleep(0.6)
    assert not budget.expired()  # 0.6 s of wall, but no work
    _spin(0.6)
    assert budget.expired()
