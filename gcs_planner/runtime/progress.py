"""The one progress display of every command (plan, dry-run, upload, download, sweep).

Each display is one line on stderr, drawn by tqdm: tqdm pads every redraw to the length of the
line before it and trims it to the terminal's width, so a shorter line never leaves the tail
of a longer one behind (the hand-written printers this replaces could: "ETA 21ss") and a long
one never wraps onto a second row that a carriage return cannot reach.

A display draws only when its stream is a terminal and the user did not ask for quiet: logs,
pipes and CI keep clean stderr. A caller may force plain lines on a stream that is no terminal
(``plan --progress`` into a log file): one line per report, at most every ``every`` seconds,
and the last one always.
"""

from __future__ import annotations

import math
import sys
import time
from typing import Protocol, TextIO

from tqdm import tqdm

from gcs_planner.runtime.terminal import on_terminal

__all__ = ["SearchProgress", "StatusLine", "on_terminal", "search_text"]


class SearchReport(Protocol):
    """What a search reports of itself (:class:`gcs_planner.core.budget.Progress` is one): the
    runtime draws it without depending on the planner."""

    labels: int
    open_routes: int
    routes_found: int
    bound: float
    seconds: float
    stage: str
    setup: str


class _Bar(tqdm):
    # tqdm's monitor thread only corrects a bar that has not been redrawn for 10 s; every
    # caller here redraws on its own schedule, and a stray thread per process is not worth it.
    monitor_interval = 0


class StatusLine:
    """One line of text kept up to date: ``show(text)`` redraws it, ``close()`` ends it.

    ``quiet`` silences it whatever the stream; ``force`` writes plain lines (at most every
    ``every`` seconds) when the stream is no terminal, where it is silent otherwise."""

    def __init__(
        self,
        stream: TextIO | None = None,
        *,
        quiet: bool = False,
        force: bool = False,
        every: float = 10.0,
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.live = not quiet and on_terminal(self.stream)
        self.plain = not quiet and force and not self.live
        self.every = every
        self._bar: tqdm | None = None
        self._last_plain = -math.inf
        self._pending = ""

    @property
    def enabled(self) -> bool:
        return self.live or self.plain

    def show(self, text: str) -> None:
        if self.live:
            if self._bar is None:
                self._bar = _Bar(
                    file=self.stream, bar_format="{desc}", dynamic_ncols=True, leave=True
                )
            self._bar.set_description_str(text, refresh=True)
        elif self.plain:
            now = time.monotonic()
            if now - self._last_plain >= self.every:
                self._last_plain = now
                self._write_plain(text)
                self._pending = ""
            else:
                self._pending = text  # written by close(): a log ends with the last state

    def _write_plain(self, text: str) -> None:
        self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        """End the line (what is printed next starts on its own); safe to call twice."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        if self._pending:
            self._write_plain(self._pending)
            self._pending = ""


class Counter:
    """Things done out of a known total, with the rate and the time left (tqdm's ETA):
    ``update(done, **fields)`` redraws at most 10 times a second, ``close()`` ends the line.

    Silent off a terminal, with ``quiet``, and for totals under ``min_total`` (a bar for three
    items flashes by unread)."""

    def __init__(
        self,
        label: str,
        total: int,
        *,
        unit: str = "item",
        stream: TextIO | None = None,
        quiet: bool = False,
        min_total: int = 0,
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.total = max(0, int(total))
        self.enabled = not quiet and self.total >= min_total and on_terminal(self.stream)
        self._bar: tqdm | None = None
        if self.enabled:
            self._bar = _Bar(
                total=self.total,
                desc=label,
                unit=f" {unit}",
                file=self.stream,
                dynamic_ncols=True,
                leave=True,
                mininterval=0.1,
            )

    def update(self, done: int, **fields: object) -> None:
        bar = self._bar
        if bar is None:
            return
        if fields:
            # Set without a redraw: the redraw below is throttled, this call is per item.
            bar.set_postfix({k: str(v) for k, v in fields.items()}, refresh=False)
        bar.update(max(0, done - bar.n))
        if done >= self.total:
            bar.refresh()  # the last state is drawn whatever the throttle

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def search_text(p: SearchReport) -> str:
    """A search's report in the user's words: labels, open routes, routes found, the bound."""
    if p.setup:
        return f"set-up: {p.setup}, {p.seconds:.1f} s"
    bound = "none open" if math.isinf(p.bound) else f"{p.bound:,.0f} m"
    stage = f"{p.stage}: " if p.stage else ""
    return (
        f"{stage}{p.seconds:.1f} s, {p.labels:,} labels, {p.open_routes:,} partial routes "
        f"open, {p.routes_found} routes found, front complete below {bound}"
    )


class SearchProgress:
    """A progress callback for a plan's :class:`~gcs_planner.core.budget.Budget`: each report
    redraws one status line; ``finish()`` ends it."""

    def __init__(
        self, stream: TextIO | None = None, *, quiet: bool = False, force: bool = False
    ) -> None:
        self.line = StatusLine(stream, quiet=quiet, force=force)

    @property
    def enabled(self) -> bool:
        return self.line.enabled

    def __call__(self, p: SearchReport) -> None:
        self.line.show(search_text(p))

    def finish(self) -> None:
        self.line.close()
