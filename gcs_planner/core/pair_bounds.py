"""A cost-to-go that knows the heading a partial route arrives with, to within a cone.

The heading-free cost-to-go bounds every leg by its shortest length over all headings, and so
forgets the turn at each point and, under climb limits, the whole helix turns a leg needs: on
dataset 2 within 15 degrees those are up to 900 m a leg. The heading at a point is not free,
though. An airplane leg from i (any heading) to j flies its horizontal part as an arc of radius
R from Pi and then the tangent to Pj; the tangent point T lies within 2R of Pi, so in the
triangle Pi, T, Pj the angle at Pj — between the heading at j and the horizontal chord i -> j —
is at most asin(2R / h_ij) when h_ij > 2R (the side opposite it is the shortest). Helices do
not change the heading. So every route that comes to j from i leaves j with a horizontal heading
in that cone, and its next leg j -> t is at least the least length over the cone,
lb(i, j, t).

That least length is bounded from below by sampling: the horizontal length H of a leg changes
with the start heading psi at a rate |dH/dpsi| = |tau . (dX)| <= h sin(angle at the target)
<= 2R (tau the heading at the target, the derivative of a CS path's length with respect to its
end being its end heading), so between samples s apart H is at least the sampled value less
R s. Over the range [H_lo, H_hi] that H can take, the flown length sqrt((H + 2 pi R k)^2 + dz^2)
is least at H_lo unless a step of the helix count k lies in the range (then at the length that
just needs no more turns). The result is never below the heading-free bound either.

With runs ("Straight at every landmark", docs/model.md) a leg first flies s_out straight on
from Pi and turns from there (its turn start S is s_out from Pi), and arrives on a tangent of
at least s_in: T then lies within 2R + s_out of Pi, so the cone's half-angle is
asin((2R + s_out) / h_ij), and the next leg's H = s_out + the CS length from Pj + s_out u(psi)
changes with psi at a rate of at most 2R + s_out (the turn start moves s_out dpsi), and is at
least s_out + s_in (its run-out and run-in).

The cost-to-go over pairs (i -> j) with these legs, G2_(i,j)(e, m), is then the ordinary one
over a graph whose nodes are the arcs of the reach graph.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from gcs_planner.core.cost_to_go import CostToGo, cost_to_go
from gcs_planner.core.kernel_records import Pairs
from gcs_planner.core.reach import ReachGraph
from gcs_planner.geometry.airplane import STEEP_SLACK_M, needed_horizontal
from gcs_planner.geometry.legs import AirplaneLegs, LegModel
from gcs_planner.scenario.model import Kind, Scenario

# Headings sampled per cone (the bound loses R * spacing per leg to the sampling).
SAMPLES = 9
# Above this many (arc, next arc) pairs the bounds cost more time than they save.
MAX_PAIRS = 400_000
# Relative rounding slack taken off every bound.
_ROUNDING = 1e-9


@dataclass(frozen=True)
class PairBounds:
    G: CostToGo  # over the arcs of the reach graph (and B)
    node_of_arc: np.ndarray  # per arc of the reach graph: its node (-1 for arcs into B)
    # The pair graph's arcs by tail: those of the node of arc (i -> j) are, in order, j's arcs
    # in the reach graph, each as long as lb(i, j, t).
    pair_ptr: np.ndarray
    pair_length: np.ndarray
    graph: ReachGraph  # the pair graph itself, and the point of each of its nodes
    point: np.ndarray
    _margins: dict[tuple[int, int], float] = field(default_factory=dict, repr=False, compare=False)

    def record(self) -> Pairs:
        """The relaxation as the compiled kernels take it."""
        return Pairs(
            True,
            self.node_of_arc.astype(np.int64),
            self.pair_ptr.astype(np.int64),
            self.pair_length,
            self.G.record(),
        )

    def legs(self, arc: int) -> np.ndarray:
        """lb(i, j, t) for every arc j -> t of the reach graph, in its order, after ``arc`` =
        (i -> j)."""
        node = int(self.node_of_arc[arc])
        return self.pair_length[self.pair_ptr[node] : self.pair_ptr[node + 1]]

    def margin(self, kept: int, new: int) -> float:
        """max over t of lb(kept, t) - lb(new, t), at least 0, for two arcs into the same point
        (remembered: the dominance tests ask for the same pairs many times)."""
        key = (kept, new)
        m = self._margins.get(key)
        if m is None:
            m = max(0.0, float(np.max(self.legs(kept) - self.legs(new), initial=0.0)))
            self._margins[key] = m
        return m

    def by_corrections(self, arc: int, e: float) -> np.ndarray | None:
        """G2 over m for a partial route that has just flown ``arc`` (an index into the reach
        graph's arcs) and carries ``e``; None when no walk from there reaches B."""
        node = int(self.node_of_arc[arc])
        if node < 0:
            return None
        return self.G.by_corrections(node, e)


def cone_half_angles(h: np.ndarray, radius: float, run_out: float = 0.0) -> np.ndarray:
    """Per leg of horizontal length h: the largest angle between the heading at its end and its
    horizontal chord, whatever the heading it starts with (pi where h <= 2R + s_out: any). The
    tangent point lies within 2R of the turn start, which lies ``run_out`` from the leg's start
    (airplane.py, ``AirplaneLeg``: run-out, helix, arc, tangent)."""
    reach = 2.0 * radius + run_out
    far = h > reach * (1.0 + 1e-12)
    ratio = np.where(far, reach / np.where(far, h, 1.0), 0.0)
    return np.where(far, np.arcsin(ratio), math.pi)


def horizontal_lengths(w: np.ndarray, psi: np.ndarray, radius: float) -> np.ndarray:
    """The horizontal CS length from the origin, heading angle ``psi``, to each horizontal
    offset ``w`` (rows x, y), for targets outside the turning circle (docs/model.md, "Leg geometry";
    the construction of ``dubins._core`` in the plane)."""
    ux, uy = np.cos(psi), np.sin(psi)
    wx, wy = w[:, 0], w[:, 1]
    h = np.hypot(wx, wy)
    a = wx * ux + wy * uy
    b = np.abs(ux * wy - uy * wx)
    R = radius
    t2 = a * a + b * (b - 2.0 * R)
    t = np.sqrt(np.maximum(t2, 0.0))
    ahead = (a > 0.0) & (t2 >= 0.0)
    a_minus_t = np.where(ahead, b * (2.0 * R - b) / np.where(ahead, a + t, 1.0), a - t)
    phi = np.arctan2(R * a_minus_t + b * t, (R - b) * R + a * t)
    phi = np.where(phi < 0.0, phi + 2.0 * math.pi, phi)
    return np.where((b <= 1e-12 * h) & (a >= 0.0), h, R * phi + t)


def pair_leg_bounds(
    xyz: np.ndarray,
    i: np.ndarray,
    j: np.ndarray,
    t: np.ndarray,
    model: AirplaneLegs,
    heading_free: np.ndarray,
) -> np.ndarray:
    """lb(i, j, t) for each triple: the least airplane leg j -> t over the headings a route
    arriving at j from i can have, never below ``heading_free`` (the leg's heading-free bound)."""
    R, run_out = model.radius, model.run_out
    # Every leg after the first leaves its point with a heading: its horizontal path holds its
    # run-out and a tangent of at least its run-in (geometry/airplane_fan.py, ``_horizontal``).
    runs = run_out + model.run_in
    come = xyz[j, :2] - xyz[i, :2]
    cone = cone_half_angles(np.hypot(come[:, 0], come[:, 1]), R, run_out)
    go = xyz[t, :2] - xyz[j, :2]
    h = np.hypot(go[:, 0], go[:, 1])
    dz = xyz[t, 2] - xyz[j, 2]
    usable = (cone < math.pi) & (h > (2.0 * R + run_out) * (1.0 + 1e-9))
    out = heading_free.astype(float).copy()
    if runs > 0.0:
        out = np.maximum(out, np.sqrt(runs * runs + dz * dz) * (1.0 - _ROUNDING))
    if not usable.any():
        return out
    idx = np.flatnonzero(usable)
    centre = np.arctan2(come[idx, 1], come[idx, 0])
    half = cone[idx]
    # H changes with psi at a rate of at most 2R + s_out: a sample is at most half a spacing away.
    slack = (2.0 * R + run_out) * half / (SAMPLES - 1)
    h_min = np.full(len(idx), np.inf)
    h_max = np.full(len(idx), -np.inf)
    for s in np.linspace(-1.0, 1.0, SAMPLES):
        psi = centre + s * half
        w = go[idx] - run_out * np.column_stack([np.cos(psi), np.sin(psi)])
        H = run_out + horizontal_lengths(w, psi, R)
        np.minimum(h_min, H, out=h_min)
        np.maximum(h_max, H, out=h_max)
    # H is never below the chord, nor below its runs
    lo = np.maximum(np.maximum(h_min - slack, h[idx]), runs)
    hi = h_max + slack
    need = needed_horizontal(dz[idx], model.max_climb_angle, model.max_descent_angle)
    # k(H) = ceil((need - slack - H) / 2 pi R) where positive; H + 2 pi R k(H) is least where
    # k steps down (= need - slack), otherwise at the range's low end.
    turn = 2.0 * math.pi * R
    x_lo = (need - STEEP_SLACK_M - hi) / turn - 1e-9
    x_hi = (need - STEEP_SLACK_M - lo) / turn + 1e-9
    steps = np.floor(x_hi) >= np.maximum(np.ceil(x_lo), 0.0)
    k_lo = np.maximum(np.ceil((need - STEEP_SLACK_M - lo) / turn), 0.0)
    flown = np.where(steps, np.minimum(need - STEEP_SLACK_M, lo), lo + turn * k_lo)
    flown = np.maximum(flown, 0.0)
    bound = np.sqrt(flown * flown + dz[idx] ** 2) * (1.0 - _ROUNDING)
    out[idx] = np.maximum(out[idx], bound)
    return out


def pair_bounds(
    scenario: Scenario,
    graph: ReachGraph,
    model: LegModel,
    stop: Callable[[], bool] | None = None,
) -> PairBounds | None:
    """G2 of ``scenario`` over ``graph`` for airplane legs with turns (None for other models,
    or when the pairs are too many to pay off). ``stop``: see ``cost_to_go``."""
    if not model.turns_in_bounds:
        return None
    n, end, start = graph.n, graph.end, graph.start
    deg = graph.degree()
    src = np.repeat(np.arange(n), deg)
    dst = graph.target.astype(np.int64)
    arcs = len(dst)
    inner = dst != end
    node_of_arc = np.full(arcs, -1, dtype=np.int64)
    node_of_arc[inner] = np.arange(int(inner.sum()))
    nodes = int(inner.sum())
    end_node, start_node = nodes, nodes + 1
    # Pairs: an arc a = (i -> j) into a correction point, then an arc b = (j -> t) out of j.
    first = np.flatnonzero(inner)
    counts = deg[dst[first]]
    if int(counts.sum()) > MAX_PAIRS:
        return None
    a = np.repeat(first, counts)
    offs = np.cumsum(counts) - counts
    b = graph.indptr[dst[a]] + (np.arange(int(counts.sum())) - np.repeat(offs, counts))
    lb = pair_leg_bounds(scenario.xyz, src[a], dst[a], dst[b], model, graph.length[b])
    head = np.where(dst[b] == end, end_node, node_of_arc[b])
    tail = node_of_arc[a]
    point = np.concatenate([dst[first], [end, start]])
    pairs = graph.expanded(tail, head, lb, point, start_node, end_node)
    is_v = scenario.kind[point] == Kind.V
    G = cost_to_go(scenario, pairs, is_v=is_v, stop=stop)
    return PairBounds(G, node_of_arc, pairs.indptr, pairs.length, pairs, point)
