"""Lengths to go that know the probability a partial route can still keep.

The cost-to-go G_j(e, m) of ``cost_to_go`` assumes every correction succeeds, so it bounds the
length of every continuation, whatever probability the route ends with. With the probability
objective that is the bound's weak spot: a partial route that has kept all its mass (say 1) can
only be pruned by found routes at least as likely to arrive, and routes certain to arrive are
long — so every partial route shorter than the shortest certain one stays open, and the search
explodes (dataset 2: the front spans 109 to 161 km).

A continuation that keeps much of the mass must survive failures. Take a partial route with
error states s of mass w_s, and a continuation that loses less than ``gap`` of the mass. The
branches from s that fail at each of the first q unreliable points the continuation visits
weigh w_s (1 - p)^q; if w_s (1 - p)^q >= gap they cannot all die, and if one of them arrives,
the one that succeeds everywhere after those q points arrives too (a success leaves less error
than a failure, and less error is never less feasible). So that continuation is flown
successfully with its first q unreliable points failing. A failed correction at y leaves the
component y corrects at min(arrival error, r/delta), and the arrival error is at least the leg
into y, at least the shortest arc into y: so the component starts at s_y = min(shortest arc
into y, r/delta) instead of 0.

G^q_j(e, m) is the least heading-free length of a walk from j to B (<= m more corrections) under
exactly that relaxation; it is the cost-to-go over a graph of q + 1 copies of the points (how
many forced failures remain) plus failed copies of the unreliable points, whose corrected
component starts at s_y. G^0 = G. Walks that visit fewer than q unreliable points count (their
branch failing at all of them weighs more still).

``bound(j, states, gap)`` combines them: for every state whose branch set must survive, G^q at
that state's own carried error (the largest q its mass allows), and the plain G at the least
carried error (some branch arrives); the pointwise maximum of valid lower bounds is one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gcs_planner.core.cost_to_go import CostToGo, cost_to_go
from gcs_planner.core.kernel_records import Failures
from gcs_planner.core.reach import ReachGraph
from gcs_planner.scenario.model import Kind, Scenario

# The most forced failures a bound considers: each costs a copy of the graph, and with p >= 0.5
# a branch failing three times weighs under 1/8 of its state.
MAX_FAILURES = 3
# Masses are sums of products: a branch set is taken to weigh at least ``gap`` only with this
# much to spare, so rounding can never make the bound claim more than the model allows. Far
# above rounding (1e-16 per operation), and below PROB_EPS, which separates the levels that
# ``gap`` is measured from (a branch of exactly 1 - p must count against a level p lower).
_MASS_SLACK = 1e-13


@dataclass(frozen=True)
class FailureBounds:
    G: CostToGo  # over the expanded graph
    n: int  # the scenario's points
    failures: int  # copies 0 .. failures
    q_fail: float  # 1 - p
    is_v: np.ndarray  # per node: its point is a V point

    def record(self) -> Failures:
        """The bounds as the compiled probes take them."""
        return Failures(
            True,
            self.G.record(),
            int(self.n),
            int(self.failures),
            float(self.q_fail),
            np.asarray(self.is_v, bool),
        )

    def _node(self, j: int, q: int) -> int:
        return q * self.n + j

    def rows(self, j: int, e: float, q: int) -> np.ndarray | None:
        """G^q_j(e, m) over m (last entry for every larger m), None when no such walk exists."""
        return self.G.by_corrections(self._node(j, q), e)

    def forced(self, weight: float, gap: float) -> int:
        """How many first failures a state of mass ``weight`` must survive in a continuation
        that loses less than ``gap`` (-1: none, the state may die whole)."""
        if weight < gap + _MASS_SLACK:
            return -1
        q = 0
        while q < self.failures and weight * self.q_fail ** (q + 1) >= gap + _MASS_SLACK:
            q += 1
        return q

    def bound(self, j: int, states: dict, gap: float) -> np.ndarray | None:
        """A lower bound per m on the length from node j of every continuation that loses less
        than ``gap`` of the mass of ``states`` ((v, h) -> mass, just after the correction at
        j's point), and reaches B; None when there is no such continuation."""
        carried = 1 if self.is_v[j] else 0  # a V point resets v: h is carried, and vice versa
        e_min = min(s[carried] for s in states)
        rows = [self.rows(j, e_min, 0)]
        for s, w in states.items():
            q = self.forced(w, gap)
            if q > 0:
                rows.append(self.rows(j, s[carried], q))
            elif q == 0:
                rows.append(self.rows(j, s[carried], 0))
        if any(r is None for r in rows):
            return None
        width = max(len(r) for r in rows)
        out = np.full(width, -np.inf)
        for r in rows:
            padded = np.empty(width)
            padded[: len(r)] = r
            padded[len(r) :] = r[-1]
            np.maximum(out, padded, out=out)
        return out


def failure_bounds(
    scenario: Scenario,
    graph: ReachGraph,
    failures: int = MAX_FAILURES,
    stop: Callable[[], bool] | None = None,
) -> FailureBounds | None:
    """The bounds G^0 .. G^failures of ``scenario`` over its reach ``graph`` (None when no
    correction can fail: every point reliable, or p = 1). ``stop``: see ``cost_to_go`` (a
    table cut short is weaker, still a lower bound)."""
    p = scenario.params.p_success
    unreliable = np.asarray(scenario.unreliable, dtype=bool)
    if p >= 1.0 or not unreliable.any() or failures <= 0:
        return None
    n, end, start = graph.n, graph.end, graph.start
    is_v_pt = scenario.kind == Kind.V
    src = np.repeat(np.arange(n), graph.degree())
    dst = graph.target.astype(np.int64)
    length = graph.length
    # Shortest arc into each point (the least error its corrected component can arrive with).
    shortest_in = np.full(n, np.inf)
    np.minimum.at(shortest_in, dst, length)
    start_failed = np.minimum(shortest_in, scenario.params.residual_m)
    fail_pts = np.flatnonzero(unreliable)
    fail_pts = fail_pts[(fail_pts != end) & (fail_pts != start)]
    # Nodes: (q, point) at q * n + point for q = 0..failures (corrected as usual), then one failed
    # copy of each unreliable point per q = 0..failures-1 (q failures still to come after it).
    plain = (failures + 1) * n
    failed_of = np.full((failures, n), -1, dtype=np.int64)
    for q in range(failures):
        failed_of[q, fail_pts] = plain + q * len(fail_pts) + np.arange(len(fail_pts))
    total = plain + failures * len(fail_pts)
    node_pt = np.concatenate([np.tile(np.arange(n), failures + 1), np.tile(fail_pts, failures)])
    own = np.zeros(total)
    own[plain:] = start_failed[node_pt[plain:]]
    # Arcs of a node at point i with q failures to come: into B as is; into an unreliable point
    # y with q > 0 its failed copy with q - 1 to come; otherwise the plain copy of y with q.
    out_src, out_dst, out_len = [], [], []
    for q in range(failures + 1):
        tail = [q * n + src]
        if q < failures:
            tail.append(failed_of[q, src])
        for t in tail:
            ok = t >= 0  # failed copies exist for unreliable points only
            s_, d_, l_ = t[ok], dst[ok], length[ok]
            head = q * n + d_
            if q > 0:
                into_fail = (d_ != end) & unreliable[d_]
                into_fail &= failed_of[q - 1, d_] >= 0
                head = np.where(into_fail, failed_of[q - 1, np.where(into_fail, d_, 0)], head)
            head = np.where(d_ == end, end, head)  # one B for every copy
            out_src.append(s_)
            out_dst.append(head)
            out_len.append(l_)
    e_src = np.concatenate(out_src)
    e_dst = np.concatenate(out_dst)
    e_len = np.concatenate(out_len)
    expanded = graph.expanded(e_src, e_dst, e_len, node_pt, start, end)
    # numpy or the compiled layer by the scenario's size, as the plain cost-to-go (loading the
    # compiled kernels costs more than small maps save).
    G = cost_to_go(scenario, expanded, is_v=is_v_pt[node_pt], own_start=own, stop=stop)
    return FailureBounds(G, n, failures, 1.0 - p, is_v_pt)
