"""A lower bound on the length still to fly from a point to B, given the error carried there.

G_j(e) = the least straight-leg length of any walk from j (just corrected, carrying e metres on
the component j did not reset) to B that keeps every arrival within its limits. Walks relax
simple routes and straight legs are never longer than flown ones, and a flown continuation that
is feasible is feasible with its (shorter) straight legs too; so G_j(e) is an admissible bound
for branch and bound with turns and with uncertain corrections alike (extra error on the
component j reset only makes the continuation harder, so assuming it 0 stays a lower bound).

Computed backwards from B in layers of legs, as labels (R, E) at j: "R metres to B, feasible iff
e <= E", kept Pareto-minimal (smaller R, larger E). A walk of a simple-route's length has at most
n - 1 legs, so n layers suffice for the bound to hold over every simple route.

The layer a label is made in is the number m of corrections it makes after j before B (a label
j -> B is layer 0). Keeping it gives the bound per number of further corrections,
G_j(e, m) = the least length with at most m more corrections, which is what prunes a partial
route with k corrections: it can only end as (>= L + G_j(e, m), k + m), and that is dominated as
soon as, for each m, a route already found has <= k + m corrections and length <= L + G_j(e, m).

On large maps the layers are slow (20,000 points: about 0.5 s a layer on two cores). A caller
with a deadline passes ``stop``: the layers end when it says so, and one last column bounds
every walk with more corrections than the layers made by the straight distance to B
(``ReachGraph.to_end``, no longer than any walk): weaker, still admissible, so a search over it
stays exact.
"""

from __future__ import annotations

import bisect
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from gcs_planner.core.kernel_records import ToGo
from gcs_planner.core.label_dominance import not_dominated, staircase, summarise
from gcs_planner.core.reach import ReachGraph, use_compiled
from gcs_planner.scenario.model import Kind, Scenario

# The fewest labels a thread is given: below, starting threads costs more than it saves.
SLICE_LABELS = 64


@dataclass(frozen=True)
class CostToGo:
    # Per point j: its labels sorted by E ascending (rows indptr[j]:indptr[j+1]); table[i, m] is
    # the least R over labels of j with E >= e_max[i] made in layer <= m. So
    # G_j(e, m) = table[first i with e_max[i] >= e, m], non-increasing in m.
    indptr: np.ndarray
    e_max: np.ndarray
    table: np.ndarray  # shape (labels, layers)
    # None: every layer was made (the bound is exact). Otherwise the layers made before
    # ``stop`` ended them: columns up to it are exact, the last bounds more corrections by the
    # straight distance to B (see the module's docstring).
    cut_at: int | None = None
    # Per point asked so far: its first row and its e_max as a list. The branch and bound asks
    # one point at a time, and bisect on a list is several times faster than searchsorted on
    # an array slice; converting only the points asked keeps large maps' tables compact.
    _keys: dict[int, tuple[int, list[float]]] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def record(self) -> ToGo:
        """The table as the compiled kernels take it."""
        return ToGo(self.indptr.astype(np.int64), self.e_max, self.table)

    @property
    def layers(self) -> int:
        return self.table.shape[1]

    def _row(self, j: int, e: float) -> int:
        keys = self._keys.get(j)
        if keys is None:
            lo, hi = int(self.indptr[j]), int(self.indptr[j + 1])
            keys = self._keys[j] = (lo, self.e_max[lo:hi].tolist())
        lo, e_max = keys
        i = bisect.bisect_left(e_max, e)
        return lo + i if i < len(e_max) else -1

    def __call__(self, j: int, e: float) -> float:
        """G_j(e): the least length to B with any number of further corrections."""
        i = self._row(j, e)
        return float(self.table[i, -1]) if i >= 0 else float("inf")

    def by_corrections(self, j: int, e: float) -> np.ndarray | None:
        """G_j(e, m) for m = 0 .. layers-1 (inf where B is out of reach with <= m more
        corrections; the last entry holds for every larger m), or None when B is out of reach."""
        i = self._row(j, e)
        return self.table[i] if i >= 0 else None


def cost_to_go(
    scenario: Scenario,
    graph: ReachGraph,
    compiled: bool | None = None,
    *,
    is_v: np.ndarray | None = None,
    own_start: np.ndarray | None = None,
    stop: Callable[[], bool] | None = None,
) -> CostToGo:
    """G of the scenario over ``graph``. ``compiled``: expand layers with the numba kernel
    (True), numpy (False) or by size (None); the same table either way.

    ``is_v`` and ``own_start`` serve graphs whose nodes are not the scenario's points (see
    ``failure_bounds``): per node, whether it is a V point, and the metres the component it
    corrects already carries right after its correction (0 for a correction that succeeds; the
    default).

    ``stop``: asked before each layer (the first is B's own arcs); True ends the layers and
    makes the table admissible without them (``cut_at``)."""
    if stop is not None and stop():  # not even B's own arcs: the straight distance alone
        return _table(graph, [], [], [], [], 0)
    compiled = use_compiled(scenario.n, compiled)
    if compiled:
        from gcs_planner.core.cost_to_go_kernel import (
            frontier_order,
            merge_frontier,
            reverse_arcs,
        )
    n = graph.n
    end = graph.end
    if is_v is None:
        is_v = scenario.kind == Kind.V
    own = np.zeros(n) if own_start is None else np.asarray(own_start, dtype=float)
    # Reverse arcs: pred -> j, excluding arcs into B (the base case) and out of A.
    src = np.repeat(np.arange(n), graph.degree())
    tgt = graph.target.astype(np.int64)
    dist = graph.length
    node, R, E = _base_labels(graph, src, tgt, dist, own)
    lim_v, lim_h = graph.lim_v, graph.lim_h
    if compiled:  # over the nodes renumbered by distance to B (mapped back at the end)
        by_end, renumber = _by_distance_to_end(graph)
        node = renumber[node]
        is_v, own, lim_v, lim_h = is_v[by_end], own[by_end], lim_v[by_end], lim_h[by_end]
    # Every label kept, with its layer, makes the table; new candidates are filtered against
    # the Pareto frontier of the labels kept so far only (``_filter``).
    kept_node, kept_R, kept_E, kept_layer = [node], [R], [E], [np.zeros(len(node), np.int64)]
    front_node, front_R, front_E = node.copy(), R.copy(), E.copy()
    if compiled:
        front_node, front_R, front_E, f_ptr = _frontier_rows(front_node, front_R, front_E, n)
    # Per point, the kept label nearest B (largest E on a tie) and the one allowing the most
    # error (nearest B on a tie): most candidates are dominated by one of the two, and testing
    # that is one gather, where the full filter sorts every candidate. Both are kept labels,
    # so whatever they drop the full filter would drop too: the labels kept are the same.
    near_R, near_e, wide_R, wide_e = (np.full(n, np.inf) for _ in range(4))
    summary = (near_R, near_e, wide_R, wide_e)
    summarise(node, R, -E, near_R, near_e, wide_R, wide_e)

    # Reverse CSR over arcs between correction points (compiled: one counting pass, where
    # the sort of tens of millions of arcs takes seconds; the same arrays).
    if compiled:
        del src, tgt
        r_ptr, r_src, r_len = reverse_arcs(
            graph.indptr, graph.target, graph.length, graph.start, end, renumber
        )
    else:
        r_ptr, r_src, r_len = _reverse_csr(graph, src, tgt, dist)

    cut_at = None
    for layer in range(1, n):
        if not len(node):
            break
        if stop is not None and stop():
            cut_at = layer
            break
        if compiled:
            arcs = (r_ptr, r_src, r_len, is_v, lim_v, lim_h, own, f_ptr, front_R, front_E)
            j, newR, newE = _fan_on_threads(node, R, E, arcs, summary)
            # Most candidates lie behind the frontier (kept as rows per point, sorted by R): the
            # fan drops them by bisection; sort the rest alone and merge them into the frontier.
            # The same labels as ``_filter`` keeps, without sorting the frontier each layer.
            order = frontier_order(j, newR, newE, n)
            keep, f_ptr, front_node, front_R, front_E = merge_frontier(
                j, newR, newE, order, f_ptr, front_R, front_E
            )
        else:
            j, newR, newE = _fan(node, R, E, r_ptr, r_src, r_len, is_v, own, graph, summary)
            keep, stays = _filter(j, newR, newE, front_node, front_R, front_E)
            front_node = np.concatenate([front_node[stays], j[keep]])
            front_R = np.concatenate([front_R[stays], newR[keep]])
            front_E = np.concatenate([front_E[stays], newE[keep]])
        node, R, E = j[keep], newR[keep], newE[keep]
        summarise(node, R, -E, near_R, near_e, wide_R, wide_e)
        kept_node.append(node)
        kept_R.append(R)
        kept_E.append(E)
        kept_layer.append(np.full(len(node), layer))
    if compiled:
        kept_node = [by_end[k] for k in kept_node]
    return _table(graph, kept_node, kept_R, kept_E, kept_layer, cut_at, compiled)


def _by_distance_to_end(graph: ReachGraph) -> tuple[np.ndarray, np.ndarray]:
    """(the nodes by distance to B, each node's rank in that order): the numbering the compiled
    layers run over. A label's predecessors are then near it in memory too, and the per-node
    arrays the fan reads at each of tens of millions of arcs stay in cache on long corridors.
    Only ``cost_to_go`` sees the numbering; the table is mapped back."""
    by_end = np.argsort(graph.to_end, kind="stable")
    renumber = np.empty(graph.n, np.int64)
    renumber[by_end] = np.arange(graph.n)
    return by_end, renumber


def _frontier_rows(
    front_node: np.ndarray, front_R: np.ndarray, front_E: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The frontier as the compiled layers keep it: rows per point, sorted by R (see
    ``cost_to_go_kernel.merge_frontier``), and each point's first row."""
    order = np.lexsort((front_R, front_node))
    front_node, front_R, front_E = front_node[order], front_R[order], front_E[order]
    f_ptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(front_node, minlength=n), out=f_ptr[1:])
    return front_node, front_R, front_E, f_ptr


def _base_labels(
    graph: ReachGraph, src: np.ndarray, tgt: np.ndarray, dist: np.ndarray, own: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The labels (node, R, E) of layer 0, the legs j -> B over the arcs (``src``, ``tgt``,
    ``dist``), Pareto-minimal per point. Not out of A: A is no correction."""
    end = graph.end
    lim_b = graph.lim_v[end]
    into_b = (tgt == end) & (src != graph.start)
    # Base: j -> B. Own component arrives with d, the carried one with e + d; both <= θ/δ.
    node = src[into_b]
    R = dist[into_b]
    E = lim_b - R
    ok = (E >= 0) & (R + own[node] <= lim_b)
    node, R, E = node[ok], R[ok], E[ok]
    # Archive for dominance: "e" of the generic filter is -E (smaller is better).
    keep = not_dominated(
        node,
        R,
        -E,
        np.zeros((len(node), 0), np.uint64),
        np.zeros(0, np.int64),
        np.zeros(0),
        np.zeros(0),
        np.zeros((0, 0), np.uint64),
    )
    return node[keep], R[keep], E[keep]


def _reverse_csr(
    graph: ReachGraph, src: np.ndarray, tgt: np.ndarray, dist: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The arcs between correction points (not into B, not out of A) by target, as CSR:
    (row pointers per target, sources, lengths), in numpy (``cost_to_go_kernel.reverse_arcs``
    groups them compiled, over the renumbered nodes)."""
    inner = (tgt != graph.end) & (src != graph.start)
    r_src, r_tgt, r_len = src[inner], tgt[inner], dist[inner]
    order = np.argsort(r_tgt, kind="stable")
    r_src, r_tgt, r_len = r_src[order], r_tgt[order], r_len[order]
    r_ptr = np.zeros(graph.n + 1, dtype=np.int64)
    np.add.at(r_ptr, r_tgt + 1, 1)
    np.cumsum(r_ptr, out=r_ptr)
    return r_ptr, r_src, r_len


def _table(
    graph: ReachGraph,
    kept_node: list[np.ndarray],
    kept_R: list[np.ndarray],
    kept_E: list[np.ndarray],
    kept_layer: list[np.ndarray],
    cut_at: int | None,
    compiled: bool = False,
) -> CostToGo:
    """The table of the labels kept, per layer; ``cut_at``: the layers ended there (``stop``)."""
    n, end = graph.n, graph.end
    if cut_at is not None:
        # Walks with cut_at or more further corrections: at least the straight distance to B,
        # whatever the error carried (E above every limit, so that every feasible e finds it).
        tail = np.flatnonzero(np.arange(n) != end)
        limits = np.concatenate([graph.lim_v, graph.lim_h])
        top = float(np.max(limits[np.isfinite(limits)], initial=0.0))  # A's are inf
        kept_node.append(tail)
        # (Less a relative 1e-9, as the pair bounds' legs: rounding may only weaken a bound.)
        kept_R.append(graph.to_end[tail] * (1.0 - 1e-9))
        kept_E.append(np.full(len(tail), 2.0 * top + 1.0))
        kept_layer.append(np.full(len(tail), cut_at))
    arch_node, arch_R, arch_E, arch_layer = (
        np.concatenate(a) for a in (kept_node, kept_R, kept_E, kept_layer)
    )

    # A label can be dominated by a later one (it stays: its layer is smaller); the suffix
    # minima below make that harmless.
    order = np.lexsort((arch_E, arch_node))
    a_node, a_E, a_R, a_layer = arch_node[order], arch_E[order], arch_R[order], arch_layer[order]
    layers = int(a_layer.max()) + 1 if len(a_layer) else 1
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.add.at(indptr, a_node + 1, 1)
    np.cumsum(indptr, out=indptr)
    # Each label's R at its layer, then a running minimum over layers (<= m) and a suffix
    # minimum over E (>= e) per point.
    if compiled:  # one pass per point (the doubling below passes the whole table log times)
        from gcs_planner.core.cost_to_go_kernel import label_table

        table = label_table(a_R, a_layer.astype(np.int64), indptr, layers)
    else:
        table = np.full((len(a_R), layers), np.inf)
        table[np.arange(len(a_R)), a_layer] = a_R
        np.minimum.accumulate(table, axis=1, out=table)
        _suffix_minima(table, indptr[a_node + 1])
    return CostToGo(indptr, a_E, table, cut_at)


def _suffix_minima(table: np.ndarray, row_end: np.ndarray) -> None:
    """Each row of ``table`` becomes the minimum of itself and the rows after it up to its
    ``row_end`` (exclusive; rows of one point are consecutive and share it), in place. By
    doubling: after the step of ``shift`` a row holds the minimum over the next 2 ``shift``
    rows of its point, so log2 of the most rows a point has steps do it, each over the whole
    table at once (one minimum per point and step took 20,000 numpy calls over pairs). Minima
    are exact: the same table as row by row."""
    live, shift = np.arange(len(table)), 1
    while len(live):
        live = live[live + shift < row_end[live]]
        table[live] = np.minimum(table[live], table[live + shift])
        shift *= 2


def _filter(
    j: np.ndarray,
    R: np.ndarray,
    E: np.ndarray,
    front_node: np.ndarray,
    front_R: np.ndarray,
    front_E: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """(which candidates (j, R, E) no frontier label and no other candidate dominates or equals,
    which frontier labels no kept candidate dominates): the frontier of the labels kept so far
    and of the new ones together, in one sort.

    Filtering against the frontier rather than every label kept is the same test: a kept label
    off the frontier is dominated by one on it, which dominates whatever it dominates. Per
    point, ``staircase`` on (R, -E), frontier labels winning ties.
    """
    m = len(j)
    if m == 0:
        return np.zeros(0, dtype=bool), np.ones(len(front_node), dtype=bool)
    touched = np.zeros(int(max(j.max(), front_node.max(initial=0))) + 1, dtype=bool)
    touched[j] = True
    near = touched[front_node]
    at = np.flatnonzero(near)
    nodes = np.concatenate([front_node[at], j])
    Rs = np.concatenate([front_R[at], R])
    es = -np.concatenate([front_E[at], E])  # smaller is better
    is_new = np.zeros(len(nodes), dtype=bool)
    is_new[len(at) :] = True
    survive = staircase(nodes, Rs, es, is_new)
    stays = np.ones(len(front_node), dtype=bool)
    stays[at] = survive[: len(at)]
    return survive[len(at) :], stays


def _fan_on_threads(
    node: np.ndarray,
    R: np.ndarray,
    E: np.ndarray,
    args: tuple[np.ndarray, ...],
    summary: tuple[np.ndarray, ...],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The compiled layer (``args``: the reverse arcs, V flags, limits, start errors and the
    frontier, as ``backward_fan`` takes them), its labels cut into one slice per thread of
    equal arc counts (the work is the arcs a label fans over: a label's own count varies a
    hundredfold), slices concatenated in label order. numba's thread count
    (NUMBA_NUM_THREADS) sets how many."""
    from numba import get_num_threads  # here: importing this module must not load numba

    from gcs_planner.core.cost_to_go_kernel import backward_fan

    packed = np.stack(summary, axis=1)
    r_ptr = args[0]
    arcs = np.cumsum(r_ptr[node + 1] - r_ptr[node])
    threads = max(1, min(get_num_threads(), len(node) // SLICE_LABELS))
    cuts = [0]
    if threads > 1 and len(arcs):
        share = arcs[-1] / threads
        cuts += [int(np.searchsorted(arcs, share * t)) for t in range(1, threads)]
    cuts.append(len(node))
    slices = list(zip(cuts[:-1], cuts[1:], strict=True))
    if len(slices) == 1:
        return backward_fan(node, R, E, 0, len(node), *args, packed)
    with ThreadPoolExecutor(len(slices)) as pool:
        parts = list(
            pool.map(lambda s: backward_fan(node, R, E, s[0], s[1], *args, packed.copy()), slices)
        )
    return tuple(np.concatenate(p) for p in zip(*parts, strict=True))  # type: ignore[return-value]


def _fan(
    node: np.ndarray,
    R: np.ndarray,
    E: np.ndarray,
    r_ptr: np.ndarray,
    r_src: np.ndarray,
    r_len: np.ndarray,
    is_v: np.ndarray,
    own: np.ndarray,
    graph: ReachGraph,
    summary: tuple[np.ndarray, ...],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The candidates (predecessor, R, E) of one backward layer that are feasible and dominated
    by neither summary label of their point (numpy; ``cost_to_go_kernel`` compiled)."""
    counts = r_ptr[node + 1] - r_ptr[node]
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros(0)
    lab = np.repeat(np.arange(len(node)), counts)
    offs = np.cumsum(counts) - counts
    arc = r_ptr[node][lab] + (np.arange(total) - offs[lab])
    j = r_src[arc]  # the predecessor, where the new label lives
    j1 = node[lab]  # the point the label was at
    d = r_len[arc]
    same = is_v[j] == is_v[j1]
    # Component j resets ("own") arrives at j1 with d; the carried one with e + d.
    lim_own = np.where(is_v[j], graph.lim_v[j1], graph.lim_h[j1])
    lim_other = np.where(is_v[j], graph.lim_h[j1], graph.lim_v[j1])
    E1 = E[lab]
    # The component j corrects starts at own[j] (0 unless j's correction failed).
    d_own = d + own[j]
    feasible = (d_own <= lim_own) & (same | (d_own <= E1))
    newE = np.where(same, np.minimum(lim_other, E1) - d, lim_other - d)
    newR = R[lab] + d
    feasible &= newE >= 0
    feasible &= ~(
        ((summary[0][j] <= newR) & (summary[1][j] <= -newE))
        | ((summary[2][j] <= newR) & (summary[3][j] <= -newE))
    )
    return j[feasible], newR[feasible], newE[feasible]
