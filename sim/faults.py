"""Seeded link faults: drop, duplicate, delay and reorder, at given rates.

A :class:`FaultInjector` sits on one direction of a link and decides, for each frame pushed
through it, what comes out and when. It never looks inside a frame, so the same class serves
outgoing packed bytes and incoming decoded messages. Decisions come from its own seeded
generator, so a run with the same seed and the same traffic injects the same faults.
"""

from __future__ import annotations

import random
from dataclasses import dataclass
from typing import Generic, TypeVar

T = TypeVar("T")


@dataclass(frozen=True)
class FaultRates:
    """Per-frame probabilities. ``delay_s`` is the longest delay; a delayed frame waits a
    uniform time in (0, delay_s]. A reordered frame is held until the next frame has gone (or
    ``delay_s`` has passed, so that the last frame of a burst is late, not lost)."""

    drop: float = 0.0
    duplicate: float = 0.0
    delay: float = 0.0
    reorder: float = 0.0
    delay_s: float = 0.05

    def __post_init__(self) -> None:
        for name in ("drop", "duplicate", "delay", "reorder"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"fault rate {name} must lie in [0, 1] (got {value!r})")
        if self.delay_s < 0:
            raise ValueError("delay_s must be >= 0")

    @property
    def any(self) -> bool:
        return any((self.drop, self.duplicate, self.delay, self.reorder))


@dataclass
class FaultCounts:
    passed: int = 0
    dropped: int = 0
    duplicated: int = 0
    delayed: int = 0
    reordered: int = 0


class FaultInjector(Generic[T]):
    """``push(frame, now)`` returns the frames to deliver now; ``due(now)`` the held frames
    whose time has come. Not thread-safe: one owner per direction."""

    def __init__(self, rates: FaultRates, seed: int = 0) -> None:
        self.rates = rates
        self.rng = random.Random(seed)
        self.counts = FaultCounts()
        self._held: list[tuple[float, int, T]] = []  # (due time, arrival order, frame)
        self._order = 0
        self._swap: tuple[float, T] | None = None  # a frame waiting to go after the next one

    def push(self, frame: T, now: float) -> list[T]:
        r = self.rates
        rng = self.rng
        if rng.random() < r.drop:
            self.counts.dropped += 1
            return []
        copies = 1
        if rng.random() < r.duplicate:
            copies = 2
            self.counts.duplicated += 1
        out: list[T] = []
        for _ in range(copies):
            if rng.random() < r.delay:
                self.counts.delayed += 1
                self._order += 1
                self._held.append((now + rng.uniform(0.0, r.delay_s) + 1e-4, self._order, frame))
                continue
            if self._swap is None and rng.random() < r.reorder:
                self.counts.reordered += 1
                self._swap = (now + r.delay_s, frame)
                continue
            out.append(frame)
            self.counts.passed += 1
            if self._swap is not None:
                out.append(self._swap[1])
                self._swap = None
        return out

    def due(self, now: float) -> list[T]:
        out: list[T] = []
        if self._swap is not None and self._swap[0] <= now:
            out.append(self._swap[1])
            self._swap = None
        if self._held:
            ready = sorted((h for h in self._held if h[0] <= now), key=lambda h: h[:2])
            if ready:
                self._held = [h for h in self._held if h[0] > now]
                out.extend(h[2] for h in ready)
        return out

    def pending(self) -> int:
        return len(self._held) + (self._swap is not None)
