"""A test's handle on "Ctrl-C at any moment": hold the process at the import of one module until a
signal comes (``GCS_PLANNER_HOLD_IMPORT=module``).

A test that sends SIGINT after a sleep hits whatever the process happens to run then, and on a
loaded machine that is not what it meant to test (issue 54: a Ctrl-C during the start-up's
imports once printed a traceback). With the variable set, the process writes one line
(:data:`HELD`, the module's name after it) to stderr when it is about to import that module and
waits there for a signal; the test sends SIGINT once it has read the line. The signal's handler
runs as it would at that moment: Python's own raises KeyboardInterrupt inside the import, the
plan's (:mod:`gcs_planner.runtime.interrupt`) sets its flag and the import goes on. Unset (every
real run), nothing is installed.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from typing import Any

VARIABLE = "GCS_PLANNER_HOLD_IMPORT"
HELD = "gcs-planner: held at the import of"


class _Hold:
    """Waits for a signal the first time ``module`` is imported."""

    def __init__(self, module: str) -> None:
        self.module = module

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> None:
        # Signals reach the main thread only: a worker thread held here would wait for ever.
        if name != self.module or threading.current_thread() is not threading.main_thread():
            return None
        sys.meta_path.remove(self)
        sys.stderr.write(f"{HELD} {name}\n")
        sys.stderr.flush()
        signal.pause()  # returns after a signal's handler has run (or raises from it)
        return None  # the import goes on with the other finders


def install_from_environment() -> None:
    """Hold at the import the environment names, if any (a test's; see the module's doc)."""
    module = os.environ.get(VARIABLE, "")
    if module and hasattr(signal, "pause"):
        sys.meta_path.insert(0, _Hold(module))
