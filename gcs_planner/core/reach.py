"""The reach graph: which point can follow which, and at what straight distance.

A leg longer than the largest error budget divided by δ can never be flown between two
corrections, so only neighbours within that radius are arcs. The graph is stored as CSR arrays
(networkx-style plain data) so that the searches expand whole label layers with numpy.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from gcs_planner.core.kernel_records import Graph
from gcs_planner.geometry.legs import AirplaneLegs, scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

# From this many points on, the compiled kernels (numba) build the graph and run the search: below
# it numpy is fast enough and the first call's compilation would cost more than it saves.
COMPILED_FROM_POINTS = 3_000
# Arcs per block when the chord graph's arcs are raised to a leg model's bounds.
_BLOCK_ARCS = 1 << 20


def use_compiled(n: int, compiled: bool | None) -> bool:
    """``compiled`` as asked, or by size when None."""
    return n >= COMPILED_FROM_POINTS if compiled is None else compiled


@dataclass(frozen=True)
class ReachGraph:
    indptr: np.ndarray  # (n+1,) int64: arcs of i are indptr[i]:indptr[i+1]
    target: np.ndarray  # (m,) int32
    length: np.ndarray  # (m,) float64, straight distance
    lim_v: np.ndarray  # (n,) float64: vertical arrival limit at each point, metres flown
    lim_h: np.ndarray  # (n,) float64
    # (n,) float64: a lower bound on the length of any walk from each point to B (the straight
    # distance, or the climb bound): what the searches prune with, never a leg they fly. The
    # last leg of a route is an arc into B (``into_end``), which the leg model may forbid.
    to_end: np.ndarray
    start: int
    end: int

    @property
    def n(self) -> int:
        return len(self.lim_v)

    @cached_property
    def into_end(self) -> np.ndarray:
        """Per point, the length of its arc into B, inf where it has none: the completions of
        the label searches. Not ``to_end``: with R = 0 and climb limits a direct leg to B that is
        too steep cannot be flown (no helix), though ``to_end`` still bounds a walk through
        other points from below. The arcs are the leg model's lower bounds (``_bounded``), so
        whether a last leg can be flown is decided where every other leg's is."""
        out = np.full(self.n, np.inf)
        arcs = np.flatnonzero(self.target == self.end)
        source = np.searchsorted(self.indptr, arcs, side="right") - 1
        # (One arc per source into B; np.minimum.at would also take the least of several.)
        np.minimum.at(out, source, self.length[arcs])
        return out

    def degree(self) -> np.ndarray:
        return np.diff(self.indptr)

    def record(
        self,
        scenario: Scenario,
        unreliable: np.ndarray,
        p_success: float,
        residual_m: float,
        kmax: int,
        crit_bit: np.ndarray,
    ) -> Graph:
        """The graph as the compiled search and probes take it, with the scenario's numbers a
        step along it needs and each critical point's bit (-1: not critical)."""
        return Graph(
            self.indptr.astype(np.int64),
            self.target,
            self.length,
            self.lim_v,
            self.lim_h,
            int(self.start),
            int(self.end),
            float(self.to_end[self.start]),
            float(scenario.initial_errors[0]),
            float(scenario.initial_errors[1]),
            np.asarray(scenario.kind, np.int64),
            np.asarray(unreliable, bool),
            float(p_success),
            float(residual_m),
            int(kmax),
            np.asarray(crit_bit, np.int64),
        )

    def expanded(
        self,
        source: np.ndarray,
        target: np.ndarray,
        length: np.ndarray,
        point_of_node: np.ndarray,
        start: int,
        end: int,
    ) -> ReachGraph:
        """A graph over nodes that each stand for one of this graph's points (copies of a
        point, or (previous point, point) pairs), from its arcs given as edge lists: the
        nodes keep their points' limits and distances to B."""
        order = np.argsort(source, kind="stable")
        indptr = np.zeros(len(point_of_node) + 1, dtype=np.int64)
        np.cumsum(np.bincount(source, minlength=len(point_of_node)), out=indptr[1:])
        return ReachGraph(
            indptr,
            target[order].astype(np.int32),
            length[order],
            self.lim_v[point_of_node],
            self.lim_h[point_of_node],
            self.to_end[point_of_node],
            start,
            end,
        )


def arrival_limits_m(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """Per point, the (vertical, horizontal) arrival limits in metres flown."""
    n = scenario.n
    lim_v = np.full(n, np.inf)
    lim_h = np.full(n, np.inf)
    for kind in (Kind.V, Kind.H, Kind.B):
        mask = scenario.kind == kind
        lim_v[mask], lim_h[mask] = scenario.params.limits_m(kind)
    return lim_v, lim_h


def build_reach_graph(scenario: Scenario, compiled: bool | None = None) -> ReachGraph:
    """Arcs i → j for every pair within reach, j never A and i never B.

    An arc is kept only if a leg of that length can arrive within j's limits when flown right
    after both errors were reset, i.e. d ≤ min(lim_v[j], lim_h[j]) — no route can use it
    otherwise. A leg from A counts from zero errors, the same test.

    ``compiled``: use the numba kernel (True), the KD-tree (False), or decide by size (None).

    Arc lengths are the scenario leg model's heading-free lower bounds: the chord for straight
    and cs3d legs; for airplane legs max(chord, |dz| / sin gamma), inf (no arc) where R = 0 and
    the leg is too steep. Every bound built on the graph is then admissible for that model.
    """
    graph = _chord_graph(scenario, compiled)
    if bounds_are_chords(scenario):
        return graph
    return _bounded(graph, scenario.xyz, scenario_leg_model(scenario))


def bounds_are_chords(scenario: Scenario) -> bool:
    """Whether the scenario's legs' heading-free lower bounds are their chords: straight and
    cs3d legs, and airplane legs with unlimited climb (no altitude change needs more path)."""
    return scenario_leg_model(scenario).chord_bounds


def _bounded(graph: ReachGraph, xyz: np.ndarray, model: AirplaneLegs) -> ReachGraph:
    """The chord graph with each arc's length raised to ``model``'s lower bound, arcs that can
    then no longer arrive within their target's limits dropped. Bounds are never shorter than
    chords, so the chord graph holds every arc that can remain. Done a block of source points
    at a time: at 20,000 points the graph has 30 M arcs, and whole-graph temporaries took GBs."""
    n, arcs = graph.n, len(graph.target)
    bound = np.empty(arcs)
    keep = np.empty(arcs, dtype=bool)
    counts = np.zeros(n, dtype=np.int64)  # arcs kept per point
    reach = np.minimum(graph.lim_v, graph.lim_h)
    first = 0
    while first < n:
        # the points whose arcs make up the next block of about _BLOCK_ARCS
        last = int(np.searchsorted(graph.indptr, graph.indptr[first] + _BLOCK_ARCS, "right"))
        last = min(n, max(last - 1, first + 1))
        lo, hi = int(graph.indptr[first]), int(graph.indptr[last])
        src = np.repeat(np.arange(first, last), np.diff(graph.indptr[first : last + 1]))
        dst = graph.target[lo:hi]
        bound[lo:hi] = model.arc_bounds(xyz[src], xyz[dst])
        keep[lo:hi] = bound[lo:hi] <= reach[dst]
        counts[first:last] = np.bincount(src[keep[lo:hi]] - first, minlength=last - first)
        first = last
    if keep.all():
        indptr, target = graph.indptr, graph.target
    else:
        indptr = np.zeros(n + 1, dtype=np.int64)
        np.cumsum(counts, out=indptr[1:])
        target, bound = graph.target[keep], bound[keep]
    # A bound of the rest of any route (a walk through other points), not of one leg.
    to_end = model.walk_bounds(np.zeros(3), xyz[graph.end][None, :] - xyz)
    return ReachGraph(
        indptr,
        target,
        bound,
        graph.lim_v,
        graph.lim_h,
        to_end,
        graph.start,
        graph.end,
    )


def _chord_graph(scenario: Scenario, compiled: bool | None) -> ReachGraph:
    xyz = scenario.xyz
    lim_v, lim_h = arrival_limits_m(scenario)
    start, end = scenario.start, scenario.end
    reach_to = np.minimum(lim_v, lim_h)
    to_end = np.linalg.norm(xyz - xyz[end], axis=1)
    if use_compiled(scenario.n, compiled):
        from gcs_planner.core.kernel import grid_arcs

        inner = reach_to[(np.arange(scenario.n) != end) & np.isfinite(reach_to)]
        radius = float(inner.max()) if len(inner) else 0.0
        indptr, dst, dist = grid_arcs(xyz, reach_to, radius, start, end, to_end)
        return ReachGraph(indptr, dst, dist, lim_v, lim_h, to_end, start, end)
    # Legs between A and correction points are no longer than the largest limit of a
    # correction point; only legs into B may be as long as theta allows. Querying the tree at
    # the smaller radius and adding the legs into B from the distances to B keeps the pair
    # search (the costliest step on dense maps) to the pairs that can be arcs.
    others = np.flatnonzero(np.arange(scenario.n) != end).astype(np.int32)
    inner = reach_to[others][np.isfinite(reach_to[others])]
    radius = float(inner.max()) if len(inner) else 0.0
    pairs = cKDTree(xyz[others]).query_pairs(r=radius, output_type="ndarray")
    # Each unordered pair i < j once (int32 halves the memory of dense maps): its distance,
    # then each direction kept if a leg that long can arrive within the target's limits.
    a = others[pairs[:, 0]]
    b = others[pairs[:, 1]]
    del pairs
    diff = xyz[a] - xyz[b]
    d = np.sqrt(np.einsum("ij,ij->i", diff, diff))
    del diff
    forward = (b != start) & (d <= reach_to[b])
    backward = (a != start) & (d <= reach_to[a])
    into_b = others[to_end[others] <= reach_to[end]]
    src = np.concatenate([a[forward], b[backward], into_b])
    dst = np.concatenate([b[forward], a[backward], np.full(len(into_b), end, dtype=np.int32)])
    dist = np.concatenate([d[forward], d[backward], to_end[into_b]])
    del a, b, d, forward, backward
    # CSR by source; a stable integer sort keeps the order deterministic (and is a radix sort).
    order = np.argsort(src, kind="stable")
    dst, dist = dst[order], dist[order]
    indptr = np.zeros(scenario.n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=scenario.n), out=indptr[1:])
    del src, order
    return ReachGraph(indptr, dst, dist, lim_v, lim_h, to_end, start, end)
