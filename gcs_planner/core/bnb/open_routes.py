"""The partial routes a best-first search keeps open on its heap (``_Open``), and what the search
over simple routes asks of its prober about one (``Probe``, answered by ``probes._Prober``).

Both sit below the search, the probes and the context that holds the prober: the probes run
searches and the search asks the prober, so neither may import the other for these."""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple, Protocol

import numpy as np

from gcs_planner.core.bnb.incumbents import _Incumbents
from gcs_planner.core.budget import Budget


class _Open(NamedTuple):
    """A partial route on the search's heap, ordered by ``f`` (then by when it was queued:
    ``tiebreak`` is unique, so the states are never compared)."""

    f: float  # the least length of any route it can become
    tiebreak: int
    length: float  # flown so far
    node: int
    corrections: int
    states: dict  # {(v, h): probability}, the error states it arrives in
    heading: np.ndarray | int | None  # the arc flown last under the pair relaxation
    path: tuple[int, ...]
    to_go: np.ndarray  # the bound to go per number of corrections more
    arc: int  # the arc flown last (-1 at A)


class Probe(Protocol):
    """Whether a partial route of the search over simple routes can still lead anywhere
    (``probes._Prober``), and which partial routes are worth not asking about."""

    def hope(self, points: Sequence[int], after: int = 1) -> None:
        """Mark the prefixes of ``points`` longer than ``after`` points hopeful: expanded
        unprobed."""

    def __call__(self, entry: _Open, inc: _Incumbents, budget: Budget) -> tuple[bool, int]:
        """(covered, labels spent) for the heap ``entry`` of a search whose routes are
        ``inc``."""
