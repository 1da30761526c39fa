"""Ctrl-C during a plan: taken as a flag, raised as KeyboardInterrupt only from Python.

Python's own SIGINT handler raises KeyboardInterrupt in whatever Python code runs next. During a
compiled (numba) search that code is often numba's own, called from C at a kernel's boundary
(``serialize._numba_unpickle`` when a kernel returns or raises) or inside an ``objmode`` block
(the search's progress tick); the C caller then returns a result with the exception still set,
and the user gets ``SystemError: CPUDispatcher(...) returned a result with an exception set``
and 37 lines of traceback instead of "interrupted" (issue 28: 5 of 5 interrupts of a
20,000-point plan).

So while a plan runs (:func:`deferred`), the handler only sets a flag. The budget
(:mod:`gcs_planner.core.budget`) reads it: its time checks answer "expired", which stops the
compiled searches at their next tick and cuts the cost-to-go layers short, and its checks that
run in plain Python (a label taken, a compiled search's return, a set-up step) raise
KeyboardInterrupt there, as does leaving :func:`deferred` with the flag set. Some steps before
the search never consult the budget (reading the scenario, its reach graph, the seeds); so the
wait stays bounded whatever step runs, a watchdog ends the process with the same one line and
exit status after :data:`GRACE` seconds, and a second Ctrl-C ends it at once.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from types import FrameType

# Seconds from a Ctrl-C to the exit when no check of the flag has come by then. Generous: a
# check normally comes within a fraction of a second, and an exit through the flag closes the
# progress line and runs the callers' clean-up, which the watchdog's hard exit cannot.
GRACE = 5.0
# What the CLI prints on an interrupt, and the status it exits with (128 + SIGINT).
MESSAGE = "gcs-planner: interrupted"
EXIT_CODE = 130

_flag = threading.Event()
_depth = 0
_watchdog: threading.Timer | None = None


def requested() -> bool:
    """Whether Ctrl-C was pressed during the plan running now (cheap: called per tick)."""
    return _flag.is_set()


def check() -> None:
    """Raise KeyboardInterrupt when Ctrl-C was pressed: call only from plain Python, never from
    code a compiled kernel calls back (``objmode``)."""
    if _flag.is_set():
        raise KeyboardInterrupt


def _hard_exit() -> None:
    # Past the grace period, or a second Ctrl-C: the process is stuck in a step that never
    # looks at the flag. os._exit skips the clean-up that could hang on the same step.
    prefix = "\n" if _on_terminal() else ""  # after a progress line, not on it
    with contextlib.suppress(OSError, ValueError):
        sys.stderr.write(f"{prefix}{MESSAGE}\n")
        sys.stderr.flush()
    os._exit(EXIT_CODE)


def _on_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def _handler(signum: int, frame: FrameType | None) -> None:
    # Never raise here: this may run inside numba's C boundary code (see the module's doc).
    global _watchdog
    if _flag.is_set():
        _hard_exit()
    _flag.set()
    _watchdog = threading.Timer(GRACE, _hard_exit)
    _watchdog.daemon = True
    _watchdog.start()


def _cancel_watchdog() -> None:
    global _watchdog
    if _watchdog is not None:
        _watchdog.cancel()
        _watchdog = None


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Take Ctrl-C as a flag inside the block, and raise KeyboardInterrupt on leaving it when
    Ctrl-C was pressed. Nested blocks share the outer one's handler.

    Left alone: other threads (signals reach the main thread only), and a process whose SIGINT
    is ignored or handled by someone else (a caller's handler is theirs to keep)."""
    global _depth
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if _depth:
        _depth += 1
        try:
            yield
        finally:
            _depth -= 1
        return
    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    _flag.clear()
    previous = signal.signal(signal.SIGINT, _handler)
    _depth = 1
    try:
        yield
    finally:
        _depth = 0
        signal.signal(signal.SIGINT, previous)
        _cancel_watchdog()
        pressed = _flag.is_set()
        _flag.clear()
    # Outside ``finally``: an exception from the block stays the one reported.
    if pressed:
        raise KeyboardInterrupt


def one_line_if_uncaught() -> None:
    """In the installed ``gcs-planner`` script, a Ctrl-C before :func:`gcs_planner.cli.main`
    runs (the script's own import of the command line) ends as one inside it does: the one
    line and exit status 130, not Python's traceback. Other exceptions are left to Python."""
    previous = sys.excepthook

    def hook(kind: type[BaseException], value: BaseException, tb: object) -> None:
        if issubclass(kind, KeyboardInterrupt):
            with contextlib.suppress(OSError, ValueError):
                sys.stderr.write(f"{MESSAGE}\n")
                sys.stderr.flush()
            os._exit(EXIT_CODE)
        previous(kind, value, tb)  # type: ignore[arg-type]

    sys.excepthook = hook
