"""A whole leg fan tested at once against the routes found, before the per-leg work.

The branch and bound extends a partial route along every arc of its point and, per arc,
propagates the error-state distribution and looks up the cost-to-go before it asks whether a
found route already covers the extension — Python work per arc, and most arcs end there. This
asks that question first, for the whole fan in one numpy comparison, with bounds that can only
be weaker than the per-arc ones:

* the error carried after the leg is at least the least error carried before it plus the leg
  (states that fail the point's limits are dropped, which only raises the least), and the
  cost-to-go G_j(e, m) grows with e — so G_j at that least error bounds G_j at the true one;
* the found routes are those at least as likely as the partial route before the leg (a leg
  never raises the surviving mass, and a lower required probability only admits more routes).

So every arc it drops, the per-arc test would have dropped too: the search, its labels and its
front are unchanged; only the work per label falls.
"""

from __future__ import annotations

import numpy as np

from gcs_planner.core.cost_to_go import CostToGo

# Segment keys add the point index times a span to E; the lookup searches slightly below e so
# that rounding in those keys can only pick a weaker (earlier) row, never a stronger one.
_SLACK = 1e-6


class FanBound:
    """G_j(e, m) for many (j, e) at once."""

    def __init__(self, G: CostToGo, n: int) -> None:
        self.table = np.vstack([G.table, np.full((1, G.layers), np.inf)])
        self.missing = len(G.table)  # the row of inf: B out of reach
        counts = np.diff(G.indptr[: n + 1])
        self.span = float(G.e_max.max()) + 1.0 if len(G.e_max) else 1.0
        owner = np.repeat(np.arange(n), counts)
        self.keys = owner * self.span + G.e_max
        self.end_of = G.indptr[1 : n + 1]

    def rows(self, j: np.ndarray, e: np.ndarray) -> np.ndarray:
        """Per (j, e): the bounds G_j(e', m) over m for some e' <= e (rows of inf where no walk
        from j reaches B carrying e)."""
        i = np.searchsorted(self.keys, j * self.span + np.maximum(e - _SLACK, 0.0), side="left")
        i = np.where(i < self.end_of[j], i, self.missing)
        return self.table[i]


def covered_fan(
    length_after: np.ndarray, corrections_after: int, rows: np.ndarray, best: np.ndarray
) -> np.ndarray:
    """Which extensions (length after the leg, ``rows`` = bounds per m of each target) found
    routes cover: for every m, one with <= corrections_after + m corrections and length <=
    L + G(m); ``best[c]`` the least found length with <= c corrections (non-increasing)."""
    m = min(rows.shape[1], len(best) - corrections_after)
    if m <= 0:
        return np.ones(len(length_after), dtype=bool)
    bound = length_after[:, None] + rows[:, :m]
    return np.all(bound >= best[corrections_after : corrections_after + m], axis=1)
