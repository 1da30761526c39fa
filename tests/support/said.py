"""A message stream for a sweep run in a thread: keeps what it was told and says when a given
phrase has been told, so that a test waits on the sweep's own words rather than on a clock."""

from __future__ import annotations

import io
import threading


class Said(io.StringIO):
    """``stream=`` of run_sweep; ``heard`` is set once ``phrase`` appears in what was written."""

    def __init__(self, phrase: str) -> None:
        super().__init__()
        self.phrase = phrase
        self.heard = threading.Event()
        self._lock = threading.Lock()

    def write(self, text: str) -> int:
        with self._lock:
            n = super().write(text)
            if self.phrase in self.getvalue():
                self.heard.set()
            return n

    def text(self) -> str:
        with self._lock:
            return self.getvalue()
