"""The probes of the branch and bound with turns (``bnb._Prober``), compiled (numba).

A probe searches the completions of one partial route in the relaxation that proved the floor
and asks whether a found route dominates every one. On dataset 2 with three objectives the
search over simple routes makes some 900 probes and 16,000 probe labels, two thirds of its time
in Python, one label at a time. The relaxation's legs come from arrays (the heading-free bounds,
or lb(i, j, t) over the cone of arrival headings), so the whole probe runs here: the same
best-first order (f, then the order of pushing), the same tests in the same order, the same
expansion as the compiled search (``expand_kernel``), the same dominance (``dominance_kernel``)
and the same nogoods (``nogood_kernel``); what is a probe's own is the test per probability
level (``cover_kernel.covers_by_level``) and what it does at B: stop at the first completion no
found route dominates. So it answers exactly as the Python probe does (tested: the same fronts,
labels and probe labels on random scenarios), only faster. Two things are left out because they
cannot change an answer: the whole-fan prefilter (``prefilter.covered_fan`` drops only arcs the
per-arc test drops) and the memo of the bounds per probability level.
"""

from __future__ import annotations

import heapq

import numpy as np

from gcs_planner.core.cover_kernel import (
    best_rows,
    covers,
    covers_by_level,
    dominated_end,
    level_tables,
    likely,
)
from gcs_planner.core.dominance_kernel import kept_dominates
from gcs_planner.core.expand_kernel import expand, new_labels, relaxed_legs
from gcs_planner.core.kernel_records import (
    NO_FAILURES,
    NO_PAIRS,
    Failures,
    Graph,
    Incumbents,
    Nogoods,
    Pairs,
    Partial,
    ToGo,
)
from gcs_planner.core.key_table_kernel import KeyTable, kept_at
from gcs_planner.core.nogood_kernel import NogoodStore, expanded_rows
from gcs_planner.runtime.jit import kernel


@kernel
def probe(
    graph: Graph,
    to_go_table: ToGo,
    pairs: Pairs,
    failures: Failures,
    found: Incumbents,
    route: Partial,
    nogood_head: KeyTable,
    nogoods: Nogoods,
    max_labels: int,
):  # noqa: ANN201  (a tuple of many arrays; see the Python side, ``CompiledProbes``)
    """One probe of ``route`` in the relaxation (``graph``'s legs, or ``pairs``' when present,
    bounded by ``to_go_table``, ``failures`` and the ceiling of ``found``): (covered, labels,
    the escaping completion's points after the partial route, and, when covered, the partial
    routes it expanded: their keys, scalars and states, to join the ``nogoods``)."""
    kmax = graph.kmax
    probs_sorted, levels = found.probs_sorted, found.levels
    has_ceil, ceil_rows = found.has_ceiling, found.ceiling_rows
    rows = best_rows(found.length, found.k, found.order, kmax)
    level_best, next_bad = level_tables(levels, probs_sorted, rows, has_ceil, ceil_rows, kmax)
    # Labels: the partial route probed is row 0; alone in the queue, its f is moot.
    labels = new_labels(route, route.L)
    empty_i = np.empty(0, np.int64)
    empty_f = np.empty(0)
    # No nogoods to add: (node, mask, L, k, mass, arc, vmin, hmin, start, count, v, h, m).
    nothing = (empty_i, empty_i, empty_f, empty_i, empty_f, empty_i, empty_f, empty_f,
               empty_i, empty_i, empty_f, empty_f, empty_f)  # fmt: skip

    # The partial route itself may be covered by a nogood already.
    first_ng = kept_at(nogood_head, route.node, route.mask_before)
    pool = labels.pool
    if first_ng >= 0 and kept_dominates(
        nogoods, nogoods.sv, nogoods.sh, nogoods.sm, first_ng, route.L, route.k,
        labels.mass[0], route.arc, labels.vmin[0], labels.hmin[0], pool[0], pool[1], pool[2],
        0, len(route.sv), pairs,
    ):  # fmt: skip
        return (True, 0, empty_i, *nothing)

    count = 0
    exhausted = True
    escape = -1
    escape_to = -1
    expanded = [np.int64(0)]
    expanded.pop()
    while len(labels.heap) > 0:
        _, _, lab = heapq.heappop(labels.heap)
        L = labels.L[lab]
        k = labels.k[lab]
        node = labels.node[lab]
        mass = labels.mass[lab]
        to_go = labels.to_go[lab]
        if covers(L, k, to_go, rows[likely(probs_sorted, mass)], kmax):
            continue
        if (failures.present or has_ceil) and covers_by_level(
            L, k, mass, to_go, kmax, levels, level_best, next_bad, has_ceil, ceil_rows,
            failures, node, pool[0], pool[1], pool[2], labels.ss[lab], labels.sn[lab],
        ):  # fmt: skip
            continue
        if count >= max_labels:
            exhausted = False
            break
        count += 1
        expanded.append(lab)
        legs = relaxed_legs(graph, pairs, node, labels.arc[lab])
        first = np.int64(0)  # (not a literal 0: expand would compile twice)
        while True:
            idx, length, arrive = expand(
                graph, to_go_table, pairs, labels, nogood_head, nogoods, lab, legs, first,
                probs_sorted, rows,
            )  # fmt: skip
            if idx < 0:
                break
            # At B: a completion no found route dominates escapes.
            if not dominated_end(found.length, found.k, found.p, length, k, arrive):
                escape = lab
                escape_to = graph.target[graph.indptr[node] + idx]
                break
            first = idx + 1
        if escape >= 0:
            break
    if escape >= 0:
        points = [np.int64(escape_to)]
        e = escape
        while e > 0:
            points.append(labels.node[e])
            e = labels.parent[e]
        path = np.empty(len(points), np.int64)
        for i in range(len(points)):
            path[i] = points[len(points) - 1 - i]
        return (False, count, path, *nothing)
    if not exhausted:
        return (False, count, empty_i, *nothing)
    # Covered: every partial route expanded is covered too (a nogood from now on).
    return (True, count, empty_i, *expanded_rows(labels, expanded))


class CompiledProbes:
    """The Python side of ``probe``: the arrays of one prober's relaxation (``bnb._Prober``),
    made once, the found routes' arrays, made again when they change, and the nogood store.

    ``ctx`` is the prober's context (``bnb._Context`` of the relaxation it probes in),
    ``critical`` its critical points (at most 62: a bit each)."""

    def __init__(self, ctx, critical: frozenset[int]) -> None:  # noqa: ANN001 (bnb._Context)
        graph = ctx.graph
        scenario = ctx.scenario
        self.ctx = ctx
        self.crit_bit = np.full(scenario.n, -1, np.int64)
        for b, point in enumerate(sorted(critical)):
            self.crit_bit[point] = b
        pairs = ctx.pair_floor
        self.graph = graph.record(
            scenario, ctx.unreliable, ctx.params.p_success, ctx.params.residual_m, ctx.kmax,
            self.crit_bit,
        )  # fmt: skip
        self.to_go = ctx.G.record()
        self.pairs = NO_PAIRS if pairs is None else pairs.record()
        self._failures: Failures = NO_FAILURES
        self._bounds: object = None  # the FailureBounds they were made of (None: none yet)
        self._found: object = None
        self._incumbents: Incumbents | None = None
        self.nogoods = NogoodStore()

    def _failure_bounds(self) -> Failures:
        """The failure bounds' record, asked again until the bounds are made (``bnb._Context
        .failures``: once the probes have spent enough labels)."""
        fb = self.ctx.failures(0)  # (the prober's: it counts the probes' labels itself)
        if fb is not self._bounds:
            self._bounds = fb
            self._failures = NO_FAILURES if fb is None else fb.record()
        return self._failures

    def _incumbent_record(self, inc) -> Incumbents:  # noqa: ANN001 (bnb._Incumbents)
        """The found routes' arrays and the ceiling per level, made again when they change
        (``_Incumbents.add`` makes a new list)."""
        if inc.found is not self._found:
            self._found = inc.found
            length = np.array([f.length for f in inc.found], float)
            k = np.array([f.corrections for f in inc.found], np.int64)
            p = np.array([f.probability for f in inc.found], float)
            levels = np.array(inc.levels(), float)
            ceiling = self.ctx.ceiling
            if ceiling is None:
                ceil_rows = np.empty((0, self.ctx.kmax + 1))
            else:
                ceil_rows = np.vstack(
                    [ceiling.least_above(float(lo)) for lo in levels]
                    + [ceiling.least_above(-np.inf)]
                )
            self._incumbents = Incumbents(
                ceiling is not None, ceil_rows, length, k, p, np.sort(p),
                np.argsort(p, kind="stable").astype(np.int64), levels,
            )  # fmt: skip
        return self._incumbents

    def __call__(
        self,
        inc,  # noqa: ANN001 (bnb._Incumbents)
        L: float,
        node: int,
        k: int,
        states: dict,
        arc: int,
        path: tuple[int, ...],
        to_go: np.ndarray,
        max_labels: int,
    ) -> tuple[bool, int, tuple[int, ...]]:
        """(covered, labels, the escaping completion's points after ``path``, empty if none)."""
        bits = self.crit_bit
        before = 0
        for point in path[:-1]:
            if bits[point] >= 0:
                before |= 1 << int(bits[point])
        mask = before | (1 << int(bits[node]) if bits[node] >= 0 else 0)
        sv = np.array([s[0] for s in states], float)
        sh = np.array([s[1] for s in states], float)
        sm = np.array(list(states.values()), float)
        route = Partial(
            float(L), int(node), int(k), sv, sh, sm, int(arc), before, mask,
            np.asarray(to_go, float),
        )  # fmt: skip
        out = probe(
            self.graph, self.to_go, self.pairs, self._failure_bounds(),
            self._incumbent_record(inc), route, self.nogoods.head, self.nogoods.store,
            int(max_labels),
        )  # fmt: skip
        covered, labels, escape = bool(out[0]), int(out[1]), out[2]
        if covered and labels:
            self.nogoods.add(*out[3:])
        return covered, labels, tuple(int(p) for p in escape)
