"""The clock of a plan's time limit stops while numba compiles (gcs_planner.runtime.work_clock): the
first plan after an install must not spend its limit on compiling kernels it compiles once."""

from __future__ import annotations

import time

from numba.core import event

from gcs_planner.core.budget import Budget
from gcs_planner.runtime import work_clock


def _compile(seconds: float, nested: bool = False) -> None:
    """A compile event of ``seconds`` as numba fires them (nested: a kernel's callee)."""
    with event.trigger_event("numba:compile", data={"dispatcher": None, "args": ()}):
        if nested:
            with event.trigger_event("numba:compile", data={"dispatcher": None, "args": ()}):
                time.sleep(seconds)
        else:
            time.sleep(seconds)


def test_the_clock_stops_while_numba_compiles() -> None:
    compiled0 = work_clock.compiling_seconds()
    wall0 = time.monotonic()
    work0 = work_clock.now()  # read after wall0 ...
    _compile(0.2)
    _compile(0.1, nested=True)  # counted once, not twice
    work = work_clock.now() - work0  # ... and before the wall's end: work <= wall - compiled
    wall = time.monotonic() - wall0
    compiled = work_clock.compiling_seconds() - compiled0
    # However busy the machine: the compiles took at least their sleeps (the nested one once:
    # twice would be >= 0.4 s only if the machine stalled), and the work clock advanced by at
    # most the wall time less what they took.
    assert 0.3 <= compiled <= wall
    assert work <= wall - compiled + 1e-9


def test_a_budget_does_not_spend_its_time_on_compiles() -> None:
    budget = Budget(time_limit=2.0)
    _compile(2.5)
    assert not budget.expired()  # 2.5 s of compile, and the limit is 2 s
    time.sleep(2.1)
    assert budget.expired()
