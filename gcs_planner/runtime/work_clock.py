"""The clock a plan's time limit runs on: wall time less the time numba spent compiling.

A time limit (``--time-limit``, 60 s by default) is a budget for the search. The first plan
after an install compiles its kernels once, 30 to 50 s on two cores and more on a busy machine;
a limit that counted that would stop the first plan short, or before it found any route, where
every later plan proves its front. So the budget's clock (:func:`now`) stops while numba
compiles: numba's compile events (``numba.core.event``, "numba:compile", nested for the kernels
a kernel calls: only the outermost counts), listened to from when numba is loaded, never
importing it (a plan that needs no kernel never loads it).
"""

from __future__ import annotations

import threading
import time
from typing import Any

from gcs_planner.runtime.compile_notice import when_numba_loads

_lock = threading.Lock()
_compiled = 0.0  # seconds of compiles that have ended, in this process
_depth = 0  # compiles under way (nested)
_since = 0.0  # when the outermost compile under way started


def now() -> float:
    """Monotonic seconds, less every second numba has spent compiling (frozen while it
    compiles)."""
    with _lock:
        t = _since if _depth else time.monotonic()
        return t - _compiled


def compiling_seconds() -> float:
    """Seconds numba has spent compiling in this process so far (compiles ended)."""
    with _lock:
        return _compiled


def _started() -> None:
    global _depth, _since
    with _lock:
        if _depth == 0:
            _since = time.monotonic()
        _depth += 1


def _ended() -> None:
    global _depth, _compiled
    with _lock:
        if _depth == 0:
            return
        _depth -= 1
        if _depth == 0:
            _compiled += time.monotonic() - _since


def _listen() -> None:
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            _started()

        def on_end(self, ev: Any) -> None:
            _ended()

    event.register("numba:compile", Listener())


when_numba_loads(_listen, "work clock")
