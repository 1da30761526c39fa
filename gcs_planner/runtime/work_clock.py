"""The clock a plan's time limit runs on: CPU seconds of the process, less numba's compiling.

A time limit (``--time-limit``, :data:`gcs_planner.core.budget.DEFAULT_TIME_LIMIT` by default)
is a budget for the search's own work. Wall time is not: beside ten busy processes on two cores
a plan gets a sixth of the machine, and the same command proved a sixth of the labels (issue 54).
The CPU time of the process
(``time.process_time``: user + system, every thread of it, so the cost-to-go's fan of threads
counts what it does) is what the plan itself did, whatever else runs, so the same command
proves the same front on a busy or a quiet machine.

The first plan after an install compiles its kernels once, for longer than many searches
take; a limit that counted that would stop the first plan short where every later plan
proves its front. So the clock (:func:`now`) stops while numba compiles: numba's compile
events (``numba.core.event``, "numba:compile", nested for the kernels a kernel calls: only the
outermost counts), listened to from when numba is loaded, never importing it (a plan that needs
no kernel never loads it).

Plans run side by side in threads of one process (a library caller's own pool) share its CPU
clock; a sweep's workers are processes of one thread each by default (gcs_planner/sweep/
runner.py), one plan at a time.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from gcs_planner.runtime.compile_notice import when_numba_loads

# The clock itself: CPU seconds of this process, every thread, user + system.
_cpu = time.process_time

_lock = threading.Lock()
_compiled = 0.0  # CPU seconds of compiles that have ended, in this process
_depth = 0  # compiles under way (nested)
_since = 0.0  # the CPU clock when the outermost compile under way started


def now() -> float:
    """CPU seconds of the process, less every second numba has spent compiling (frozen while
    it compiles)."""
    with _lock:
        t = _since if _depth else _cpu()
        return t - _compiled


def compiling_seconds() -> float:
    """CPU seconds numba has spent compiling in this process so far (compiles ended)."""
    with _lock:
        return _compiled


def _started() -> None:
    global _depth, _since
    with _lock:
        if _depth == 0:
            _since = _cpu()
        _depth += 1


def _ended() -> None:
    global _depth, _compiled
    with _lock:
        if _depth == 0:
            return
        _depth -= 1
        if _depth == 0:
            _compiled += _cpu() - _since


def _listen() -> None:
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            _started()

        def on_end(self, ev: Any) -> None:
            _ended()

    event.register("numba:compile", Listener())


when_numba_loads(_listen, "work clock")
