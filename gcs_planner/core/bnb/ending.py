"""What a search of the branch and bound says when it ends (``_ending``), in Python or compiled:
its routes found, the lower bounds the partial routes it left open still allow, and which front
points are proven."""

from __future__ import annotations

import math
import time

import numpy as np

from gcs_planner.core.bnb.context import _Context
from gcs_planner.core.bnb.incumbents import BnbResult, _Incumbents
from gcs_planner.core.proof import lower_bounds, settled


def _ending(
    ctx: _Context,
    inc: _Incumbents,
    live: list[tuple[float, float, int, np.ndarray, float]],
    labels: int,
    t0: float,
    exhausted: bool,
    probe_labels: int = 0,
) -> BnbResult:
    """A search's result from its found routes and the partial routes it left open that no
    found route covers (``live``: f, L, k, bounds to go, mass)."""
    found = sorted(inc.found, key=lambda g: (g.corrections, g.length))
    open_bound = min((e[0] for e in live), default=math.inf)
    open_routes = [e[1:] for e in live]
    lower = lower_bounds(found, open_routes)
    proven = settled(found, open_routes, inc.best, ctx.kmax, ctx.probability)
    return BnbResult(
        found,
        lower,
        not live,
        labels,
        time.perf_counter() - t0,
        exhausted,
        len(live),
        open_bound,
        proven=proven,
        probe_labels=probe_labels,
    )
