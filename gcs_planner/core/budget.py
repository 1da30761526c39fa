"""The user's budget for a search that may not finish: labels, seconds, and what to show meanwhile.

A branch and bound proves its front by exhausting its queue; on hard scenarios that can take
longer than a planner at the console waits. The budget says when to stop (a number of labels, a
time limit, or both, each the user's choice), and the search then reports what it has proven so
far. One budget is shared by every round of one plan (relaxation rounds, the straight-leg
floor), so the limits are the user's total, not per round.

The time limit counts CPU seconds of the plan's process, less numba's compiling
(:mod:`gcs_planner.runtime.work_clock`), not the wall clock: the same command proves the same
front on a busy machine as on a quiet one. It is checked between labels, never inside one: a
search stops within one label's work of the limit. It covers the bounds a search builds first
too (cost-to-go layers, the pair and failure bounds, the seeds), which are cut short or skipped
once it has passed; reading the scenario and building its reach graph come before it can act.
Progress is reported to a callback at most every ``every`` seconds of the wall clock (what a
user watches), so a slow terminal never slows the search (the console's callback is
:class:`gcs_planner.runtime.progress.SearchProgress`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

from gcs_planner.runtime import interrupt, work_clock

# The defaults of the CLI, plan() and sweeps: a time limit (CPU seconds), no label limit. A
# label count means nothing to a user and stops hard scenarios far short of what a minute
# proves (issue 29: a 20,000-point corridor needs 10,403 labels, a 60-point R = 1000 m
# scenario more than 5,000 to prove it infeasible); seconds are what a user waits for, and
# CPU seconds prove the same front on a busy machine as on a quiet one (issue 54).
DEFAULT_MAX_LABELS: int | None = None
DEFAULT_TIME_LIMIT: float | None = 60.0


@dataclass(frozen=True)
class Progress:
    """How far a proof has got: labels expanded, partial routes still open, routes found, and
    the least length an open partial route can still reach (the front is complete below it)."""

    labels: int
    open_routes: int
    routes_found: int
    bound: float
    seconds: float
    stage: str = ""
    # What the set-up before the search is building (empty once the search runs): on large
    # maps the bounds take seconds, and a console that shows nothing meanwhile looks hung.
    setup: str = ""


ProgressCallback = Callable[[Progress], None]


class Budget:
    """Labels and seconds a plan may spend; ``None`` for either means unlimited.

    ``max_labels`` is per search (each relaxation round and fallback of one search shares it),
    the time limit is the whole plan's: see :meth:`share`."""

    def __init__(
        self,
        max_labels: int | None = None,
        time_limit: float | None = None,
        progress: ProgressCallback | None = None,
        every: float = 0.5,
    ) -> None:
        if max_labels is not None and max_labels < 0:
            raise ValueError(f"max_labels must be >= 0, not {max_labels}")
        if time_limit is not None and not (time_limit >= 0 and math.isfinite(time_limit)):
            raise ValueError(f"time_limit must be finite seconds >= 0, not {time_limit}")
        self.max_labels = max_labels
        self.time_limit = time_limit
        self.progress = progress
        self.every = every
        self.start = work_clock.now()
        self.deadline = None if time_limit is None else self.start + time_limit
        self.spent = 0
        # Labels of every search of this plan (kept on the root: each search's share has its
        # own ``spent``), for the statement's "after N labels"; probes count apart.
        self.used = 0
        self._next_report = time.monotonic() + every
        self._root = self
        # Which limit stopped a search of this plan ("labels" or "time"; None while none has).
        self.stopped_by: str | None = None
        self.stage = ""

    def share(self, fraction: float = 1.0, stage: str = "") -> Budget:
        """A budget for one search of this plan: its own label count, and at most ``fraction``
        of the time left (so an early stage cannot take all of it from the last)."""
        child = Budget(self.max_labels, None, self.progress, self.every)
        child.start = self.start
        child._root = self._root
        child._next_report = self._next_report
        child.time_limit = self.time_limit
        if self.deadline is not None:
            now = work_clock.now()
            child.deadline = min(self.deadline, now + fraction * max(0.0, self.deadline - now))
        child.stage = stage
        return child

    def probe(self, max_labels: int) -> Budget:
        """A budget for a probe inside a search: its own label count, this budget's deadline,
        and no progress; running out stops the probe, not the search."""
        child = Budget(max_labels)
        child.deadline = self.deadline
        return child

    def elapsed(self) -> float:
        return work_clock.now() - self.start

    def expired(self) -> bool:
        """Whether the time limit has passed (a limit of 0 always has): the set-up before a
        search asks this between its steps, and skips or cuts short what only speeds the proof
        (``cost_to_go``'s ``stop``).

        A Ctrl-C counts as expired: this runs inside the compiled search's ``objmode`` tick,
        where raising would escape as a SystemError (see :mod:`gcs_planner.runtime.interrupt`), so
        the
        search stops cleanly and :meth:`stopped` raises once back in Python."""
        if interrupt.requested():
            return True
        return self.deadline is not None and (
            self.time_limit == 0 or work_clock.now() >= self.deadline
        )

    def take(self) -> bool:
        """Spend one label; False (and nothing spent) when the budget is used up. Raises
        KeyboardInterrupt after a Ctrl-C (the Python search calls this between labels)."""
        interrupt.check()
        if self.max_labels is not None and self.spent >= self.max_labels:
            return self._stop("labels")
        # A time limit of 0 stops before the first label: deterministic, whatever the machine.
        if self.expired():
            return self._stop("time")
        self.spent += 1
        self._root.used += 1
        return True

    def _stop(self, why: str) -> bool:
        self.stopped_by = why
        self._root.stopped_by = why
        return False

    def stopped(self, why: str, labels: int) -> None:
        """Record ``labels`` spent outside ``take`` (a compiled search counts its own) and,
        unless ``why`` is empty, that the labels ("labels") or the time limit ("time") stopped
        the search. Raises KeyboardInterrupt after a Ctrl-C: the compiled search returns here,
        in Python, when :meth:`expired` stopped it for one."""
        interrupt.check()
        self.spent += labels
        self._root.used += labels
        if why:
            self._stop(why)

    def due(self) -> bool:
        """Whether a progress report is due (cheap: called once per label)."""
        if self.progress is None:
            return False
        now = time.monotonic()
        if now < self._next_report:
            return False
        self._next_report = now + self.every
        return True

    def setup(self, what: str) -> None:
        """Report, when one is due, that the set-up is building ``what``; raises
        KeyboardInterrupt after a Ctrl-C (the set-up's steps call this from Python)."""
        interrupt.check()
        if self.progress is not None and self.due():
            self.progress(Progress(0, 0, 0, math.inf, self.elapsed(), self.stage, setup=what))

    def report(self, labels: int, open_routes: int, found: int, bound: float) -> None:
        if self.progress is not None:
            self.progress(Progress(labels, open_routes, found, bound, self.elapsed(), self.stage))

    def describe(self) -> str:
        """The limits in the user's words, for statements."""
        parts = []
        if self.time_limit is not None:
            parts.append(f"{self.time_limit:g} s of CPU")
        if self.max_labels is not None:
            parts.append(f"{self.max_labels:,} labels per search")
        return " and ".join(parts) if parts else "no limit"

    def advice(self) -> str:
        """What stopped the search, and which flag to raise: a statement that only says "not
        proven" leaves the user guessing which of two limits to change."""
        used = self._root.used
        if self.stopped_by == "time" and self.time_limit is not None:
            return (
                f"stopped by the {self.time_limit:g} s CPU time limit after {used:,} labels; raise "
                "--time-limit (library: time_limit=) to search further"
            )
        if self.stopped_by == "labels" and self.max_labels is not None:
            return (
                f"stopped by the limit of {self.max_labels:,} labels per search after {used:,} "
                "labels; raise --max-labels or leave it unset (library: max_labels=None) to "
                "search further"
            )
        return "raise --time-limit or --max-labels (library: time_limit=, max_labels=)"
