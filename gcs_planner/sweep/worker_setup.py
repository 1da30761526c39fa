"""Dask preload of the sweep's own local workers: they ignore SIGINT.

A Ctrl-C in a terminal reaches the whole process group, the local cluster's worker processes
included; left at Python's default they died with a KeyboardInterrupt traceback each and their
cells were lost while the sweep waited for them. The client owns the stop: it takes the Ctrl-C
as a flag, saves the table and closes the cluster. Loaded by the worker process itself (Dask's
``distributed.worker.preload``), so a worker its nanny restarts ignores SIGINT too.
"""

from __future__ import annotations

import signal
import threading


def ignore_sigint() -> None:
    """SIGINT ignored in this process (only the main thread may set a handler)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


ignore_sigint()


def dask_setup(worker: object) -> None:
    """Dask's preload hook, run when the worker starts: SIGINT ignored again, in case anything
    since the import set a handler."""
    ignore_sigint()
