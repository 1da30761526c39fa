"""The transfer bar of upload and download: items sent or read out of the mission's count, the
rate and the time left, on stderr (see :mod:`gcs_planner.runtime.progress`, the one display of every
command); silent when stderr is not a terminal or the user asked for quiet."""

from __future__ import annotations

from typing import TextIO

from gcs_planner.runtime.progress import Counter


class Progress(Counter):
    """``update(done)`` redraws at most 10 times a second; ``close()`` ends the line.
    ``enabled`` False: silent (``--quiet``); None or True: drawn when the stream is a terminal.
    Missions under ``min_total`` items go by too fast for a bar."""

    def __init__(
        self,
        label: str,
        total: int,
        *,
        stream: TextIO | None = None,
        enabled: bool | None = None,
        min_total: int = 20,
    ) -> None:
        super().__init__(
            label, total, unit="item", stream=stream, quiet=enabled is False, min_total=min_total
        )
