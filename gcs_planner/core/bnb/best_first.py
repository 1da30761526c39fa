"""One best-first search of the branch and bound in Python (``_BestFirst``), step by step: its
set-up and seeds, the tests a popped partial route must pass, the expansion of one by a leg to
each next point, and the partial routes it leaves open. ``search._search`` runs it (and says
what it searches); the compiled search (``search_kernel``) holds to its order of operations."""

from __future__ import annotations

import bisect
import heapq
import itertools
import math
import sys
import time
from collections.abc import Sequence

import numpy as np

from gcs_planner.core.bnb.context import _Context
from gcs_planner.core.bnb.dominance import _dominated_by, _kept, _key, _larger
from gcs_planner.core.bnb.incumbents import BnbResult, Found, _dominated, _Incumbents
from gcs_planner.core.bnb.open_routes import _Open
from gcs_planner.core.budget import Budget
from gcs_planner.core.prefilter import FanBound, covered_fan
from gcs_planner.core.probability import propagate
from gcs_planner.runtime import work_clock
from gcs_planner.scenario.model import Kind


class _BestFirst:
    """One best-first search in Python, between its steps: the heap, the routes found
    (``inc``), the partial routes kept per point (``archive``) and the labels spent. The steps
    run in the order ``search._search`` gives them: ``start``, ``run`` (each popped partial
    route ``_admitted``, then ``_expand``-ed), then ``probe_result`` or ``still_open``."""

    def __init__(
        self,
        ctx: _Context,
        critical: frozenset[int] | None,
        budget: Budget,
        origin: _Open | None,
        incumbents: _Incumbents | None,
        nogoods: dict | None,
    ) -> None:
        self.t0 = time.perf_counter()
        self.ctx, self.critical, self.budget, self.origin = ctx, critical, budget, origin
        scenario, graph = ctx.scenario, ctx.graph
        self.start_point, self.end = graph.start, graph.end
        self.relaxed = critical is not None
        self.fan = FanBound(ctx.G, scenario.n)
        self.is_v_point = scenario.kind == Kind.V
        self.options = options = ctx.options
        model = ctx.model
        self.fast_legs = getattr(model, "compiled_lengths", None) if options.compiled_legs else None
        # Once numba is loaded (a search before this one needed it) the compiled legs cost
        # nothing to start: from the first label.
        self.legs_from = -1 if "numba" in sys.modules else options.compiled_legs_from
        # Per (point, critical points visited): the partial routes kept (``_kept``), sorted by
        # length, and their lengths.
        self.archive: dict[tuple[int, frozenset[int]], tuple[list[float], list[tuple]]] = {}

        self.probe = origin is not None
        self.inc = incumbents if incumbents is not None else _Incumbents(ctx.kmax)
        self.prober = None if self.relaxed else ctx.prober
        self.probe_labels = 0
        self.expanded: list[tuple[tuple, tuple]] = []
        self.nogoods = {} if nogoods is None else nogoods

        self.ceiling = ctx.ceiling
        # Straight legs: queue a partial route by its least continuation that no found route
        # dominates (``least_open``), not by its least continuation of all, so that partial
        # routes only the few-corrections end still needs wait until routes there are found,
        # instead of being expanded as soon as their many-corrections continuations look short.
        # Any order exhausts the same queue: the order only decides how soon routes are found.
        self.by_open = ctx.open_order and self.relaxed and not self.probe

        # G2: for this model's legs, or in the search over the pair relaxation, whose
        # cost-to-go it is exactly (never in the heading-free relaxation, whose legs are
        # shorter).
        self.pairs = ctx.pair_floor if self.relaxed else ctx.pairs
        self.pair_floor = ctx.pair_floor
        self.labels = 0
        self.exhausted = True
        self.escaped: Found | None = None  # a probe's relaxed completion no incumbent dominates
        self.heap: list[_Open] = []
        self.counter = itertools.count()

    def by_level(
        self,
        length: float,
        k: int,
        j: int,
        states: dict,
        mass: float,
        to_go: np.ndarray | None,
    ) -> bool:
        """Whether found routes cover the partial route, tested per probability level.
        ``to_go``: the label's bound over every continuation (it holds for each level too)."""
        if (self.relaxed and not self.probe) or j == self.start_point:
            return False
        failures = self.ctx.failures(self.labels)  # (a probe's: the probes' labels before it)
        ceiling = self.ceiling
        if failures is None and ceiling is None:
            return False
        if failures is None:
            return self.inc.covers_by_level(length, k, mass, lambda gap: to_go, ceiling)
        memo: dict[tuple[int, ...], np.ndarray | None] = {}

        def bound(gap: float) -> np.ndarray | None:
            key = tuple(failures.forced(w, gap) for w in states.values())
            if key not in memo:
                rows = failures.bound(j, states, gap)
                memo[key] = None if rows is None or to_go is None else _larger(rows, to_go)
            return memo[key]

        return self.inc.covers_by_level(length, k, mass, bound, ceiling)

    def start(self, seeds: Sequence[Sequence[int]]) -> None:
        """The seeds as routes found, and the heap: the probe's ``origin``, else A alone."""
        ctx, inc = self.ctx, self.inc
        for points in seeds:
            inc.offer(ctx.seed(points))
        if self.prober is not None:
            for route in inc.found:
                self.prober.hope(route.points)
        scenario, graph, start = ctx.scenario, ctx.graph, self.start_point
        heading_a = (
            None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)
        )
        # A carries no error and makes no correction: |A - B| bounds every route, whatever its
        # corrections.
        self.heap = [
            self.origin
            or _Open(
                float(graph.to_end[start]),
                next(self.counter),
                0.0,
                start,
                0,
                {scenario.initial_errors: 1.0},
                # The pair relaxation: no arc flown yet.
                heading_a if self.pair_floor is None else None,
                (start,),
                np.array([graph.to_end[start]]),
                -1,
            )
        ]

    def run(self) -> None:
        """Pop and expand partial routes until the heap empties, the budget ends (the popped
        one goes back) or a probe finds a completion that escapes."""
        heap, inc, budget = self.heap, self.inc, self.budget
        while heap:
            entry = heapq.heappop(heap)
            mass = sum(entry.states.values())
            if not self._admitted(entry, mass):
                continue
            if not budget.take():
                heapq.heappush(heap, entry)
                self.exhausted = False
                break
            self.labels += 1
            if self.probe:
                node, path = entry.node, entry.path
                state = _kept(entry.length, entry.corrections, entry.states, mass, entry.arc)
                self.expanded.append((_key(self.critical, node, path[:-1]), state))
            if budget.due():
                budget.report(self.labels, len(heap), len(inc.found), entry.f)
            self._expand(entry, mass)
            if self.escaped is not None:
                break

    def _admitted(self, entry: _Open, mass: float) -> bool:
        """Whether the popped ``entry`` is still worth a label: no route found since it was
        queued covers it (straight legs: re-queued behind its least open continuation, if that
        grew) and the prober does not prove it covered."""
        f, _, L, node, k, states, _heading, _path, to_go, _arc = entry
        inc = self.inc
        # Routes found since this label was queued may now cover it.
        if self.by_open:
            least = inc.least_open(L, k, to_go, mass)
            if least == math.inf:
                return False
            if least > f:  # queued before routes that now cover its shortest continuations
                heapq.heappush(self.heap, entry._replace(f=least))
                return False
        elif inc.covers(L, k, to_go, mass) or self.by_level(L, k, node, states, mass, to_go):
            return False
        prober = self.prober
        if (
            prober is not None
            and node != self.start_point
            and self.labels >= self.options.probe_from
        ):
            covered, spent = prober(entry, inc, self.budget)
            self.probe_labels += spent
            if covered:
                return False
        return True

    def _fan(
        self, entry: _Open, mass: float
    ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
        """(first arc, targets, flown lengths, headings at them, which to try) of the legs out
        of ``entry``'s point: those within the targets' limits from the least errors carried,
        less the whole fan that found routes cover (``prefilter``)."""
        _, _, L, node, k, states, heading, _, _, _ = entry
        graph, model, pair_floor = self.ctx.graph, self.ctx.model, self.pair_floor
        lo, hi = graph.indptr[node], graph.indptr[node + 1]
        targets = graph.target[lo:hi].astype(np.int64)
        straight = graph.length[lo:hi]
        if pair_floor is not None:  # the heading is the arc flown last (None at A)
            flown = straight if heading is None else pair_floor.legs(heading)
            headings = lo + np.arange(hi - lo)
        elif model.carries_heading:
            xyz = self.ctx.scenario.xyz
            # Compiled airplane legs once the search proves long (numba loads in a fraction
            # of a second: short searches never pay for it).
            fast_legs = self.fast_legs
            if fast_legs is not None and heading is not None and self.labels > self.legs_from:
                flown, headings = fast_legs(xyz[node], heading, xyz[targets])
            else:
                flown, headings = model.lengths(xyz[node], heading, xyz[targets])
        else:  # heading-free legs are as long as the graph's arcs
            flown, headings = straight, None
        v_min = min(s[0] for s in states)
        h_min = min(s[1] for s in states)
        ok = (v_min + flown <= graph.lim_v[targets]) & (h_min + flown <= graph.lim_h[targets])
        inner = np.flatnonzero(ok & (targets != self.end))
        carried = np.where(self.is_v_point[targets[inner]], h_min, v_min) + flown[inner]
        rows = self.fan.rows(targets[inner], carried)
        ok[inner[covered_fan(L + flown[inner], k + 1, rows, self.inc.best(mass))]] = False
        return lo, targets, flown, headings, ok

    def _expand(self, entry: _Open, mass: float) -> None:
        """Push the partial routes one leg longer than ``entry`` that no found route covers
        and no kept one dominates, and add the routes it completes (a probe stops at the first
        completion no found route dominates: it escapes)."""
        _, _, L, _, k, states, _, path, _, _ = entry
        lo, targets, flown, headings, ok = self._fan(entry, mass)
        ctx, inc, heap, critical = self.ctx, self.inc, self.heap, self.critical
        relaxed, probe, by_open, end = self.relaxed, self.probe, self.by_open, self.end
        kmax, kind_of, unreliable, params, G = (
            ctx.kmax,
            ctx.kind_of,
            ctx.unreliable,
            ctx.params,
            ctx.G,
        )
        pairs, pair_floor, archive, nogoods = (
            self.pairs,
            self.pair_floor,
            self.archive,
            self.nogoods,
        )
        for idx in np.flatnonzero(ok):
            j = int(targets[idx])
            # (Over walks only critical points may not repeat: a set look-up first, the
            # path's tuple scanned only for those.)
            if (j in critical and j in path) if relaxed else j in path:
                continue
            d = float(flown[idx])
            is_end = j == end
            if not is_end and k + 1 > kmax:
                continue
            new_states, _ = propagate(states, d, kind_of[j], bool(unreliable[j]), params)
            if not new_states:
                continue
            new_mass = sum(new_states.values())
            nL = L + d
            if is_end:
                new_mass = min(1.0, new_mass)
                if not _dominated(inc.found, nL, k, new_mass):
                    if probe:
                        self.escaped = Found(nL, k, new_mass, path + (j,))
                        return
                    inc.add(Found(nL, k, new_mass, path + (j,)))
                continue
            is_v = kind_of[j] == Kind.V
            # G is non-decreasing in e: the least carried error bounds every state.
            e_min = min(st[1] if is_v else st[0] for st in new_states)
            g = G.by_corrections(j, e_min)
            if pairs is not None and g is not None:
                g2 = pairs.by_corrections(int(lo + idx), e_min)
                g = None if g2 is None else _larger(g, g2)
            # (The test per probability level is left to the pop: it costs more than the
            # partial routes it would keep off the heap.)
            if by_open:
                least = inc.least_open(nL, k + 1, g, new_mass)
                if least == math.inf:
                    continue
            elif inc.covers(nL, k + 1, g, new_mass):
                continue
            if relaxed:
                key = _key(critical, j, path)
                lengths, kept = archive.setdefault(key, ([], []))
                arc_in = int(lo + idx)
                state = _kept(nL, k + 1, new_states, new_mass, arc_in)
                # Kept by length: only those no longer than this one can dominate it.
                shorter = bisect.bisect_right(lengths, nL)
                if _dominated_by(kept, state, pair_floor, shorter) or (
                    probe and _dominated_by(nogoods.get(key, ()), state, pair_floor)
                ):
                    continue
                lengths.insert(shorter, nL)
                kept.insert(shorter, state)
            new_heading = None if headings is None else headings[idx]
            heapq.heappush(
                heap,
                _Open(
                    least if by_open else nL + float(g[-1]),
                    next(self.counter),
                    nL,
                    j,
                    k + 1,
                    new_states,
                    new_heading,
                    path + (j,),
                    g,
                    int(lo + idx),
                ),
            )

    def probe_result(self) -> BnbResult:
        """A probe's answer: ``optimal`` when it proved every completion covered (then so is
        every partial route it expanded: they join the nogoods), else the completion that
        escaped, if one did."""
        covered = self.exhausted and self.escaped is None
        if covered:  # so is every partial route the probe expanded
            for key, state in self.expanded:
                self.nogoods.setdefault(key, []).append(state)
        witness = [] if self.escaped is None else [self.escaped]
        seconds = time.perf_counter() - self.t0
        return BnbResult(witness, [], covered, self.labels, seconds, self.exhausted)

    def still_open(self) -> list[tuple[float, float, int, np.ndarray, float]]:
        """The partial routes left on the heap that no found route covers, as ``_ending`` takes
        them: (f, L, k, bounds to go, mass)."""
        heap, inc, budget = self.heap, self.inc, self.budget
        live = []
        # Which open partial routes a found route covers only sharpens the statement's bounds,
        # and a search the time limit stopped may leave hundreds of thousands open: past the
        # limit plus ``ending_grace`` the rest stay open unexamined, bounds and "optimal"
        # marks only weaker for it, never wrong.
        stop_at = None if budget.deadline is None else budget.deadline + self.options.ending_grace
        for at, e in enumerate(heap):
            if stop_at is not None and at % 1024 == 0 and work_clock.now() > stop_at:
                live.extend(map(_row, heap[at:]))
                break
            row = _row(e)
            _, L, k, to_go, mass = row
            if not inc.covers(L, k, to_go, mass) and not self.by_level(
                L, k, e.node, e.states, mass, to_go
            ):
                live.append(row)
        return live


def _row(e: _Open) -> tuple:
    """An open partial route as ``_ending`` takes it: (f, L, k, bounds to go, mass)."""
    return (e.f, e.length, e.corrections, e.to_go, sum(e.states.values()))
