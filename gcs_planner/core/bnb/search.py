"""One best-first search of the branch and bound (``_search``), in Python or compiled
(``search_kernel``), and what it says when it ends (``_ending``)."""

from __future__ import annotations

import bisect
import heapq
import itertools
import math
import sys
import time
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from gcs_planner.core.bnb.context import _Context
from gcs_planner.core.bnb.dominance import _dominated_by, _kept, _key, _larger
from gcs_planner.core.bnb.incumbents import BnbResult, Found, _dominated, _Incumbents
from gcs_planner.core.budget import Budget
from gcs_planner.core.kernel_records import NO_PAIRS, Legs, Seeds
from gcs_planner.core.prefilter import FanBound, covered_fan
from gcs_planner.core.probability import propagate
from gcs_planner.core.proof import lower_bounds, settled
from gcs_planner.geometry.legs import KernelLegs
from gcs_planner.runtime import work_clock
from gcs_planner.scenario.model import Kind

# Critical points the compiled search and probes carry as bits of a mask.
MAX_COMPILED_CRITICAL = 62


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


def _search(
    ctx: _Context,
    critical: frozenset[int] | None,
    budget: Budget,
    seeds: Sequence[Sequence[int]],
    *,
    origin: _Open | None = None,
    incumbents: _Incumbents | None = None,
    nogoods: dict | None = None,
    compiled: bool = True,
) -> BnbResult:
    """One best-first search. ``critical`` None: whole simple routes, no dominance (turns, or
    the sound fallback). Otherwise walks that may not revisit a critical point, with dominance
    among partial routes at the same point that visited the same critical points.

    A probe (``origin``, a heap entry of another search, and that search's ``incumbents``)
    searches the completions of one partial route and stops at the first that no incumbent
    dominates; it adds no route. Its result is ``optimal`` when it proved that none exists;
    then every partial route it expanded is covered too and joins ``nogoods`` (by ``_key``),
    which prune the partial routes of later probes that continue no better.

    ``compiled`` False keeps a search over walks in Python (``search_kernel`` otherwise runs
    it once it needs more than ``Options.trial`` labels)."""
    legs_mode = None if origin is not None or not compiled else _legs_mode(ctx, critical)
    left = None if budget.max_labels is None else budget.max_labels - budget.spent
    if legs_mode is not None and critical is not None:
        if "gcs_planner.core.search_kernel" in sys.modules:  # loaded: no trial needed
            return _compiled_search(ctx, critical, budget, seeds, legs_mode)
    trial_labels = ctx.options.trial
    if legs_mode is not None and critical is not None and (left is None or left > trial_labels):
        # Compiled once the search proves long: a short one never loads numba. The trial is
        # the same search, so starting over loses nothing but its time.
        trial_budget = budget.probe(trial_labels)
        trial = _search(ctx, critical, trial_budget, seeds, compiled=False)
        if trial.exhausted or trial_budget.stopped_by == "time":
            budget.stopped("" if trial.exhausted else "time", trial.labels)
            return trial
        return _compiled_search(ctx, critical, budget, seeds, legs_mode)
    t0 = time.perf_counter()
    scenario, params, model, graph, G = ctx.scenario, ctx.params, ctx.model, ctx.graph, ctx.G
    kmax, kind_of, unreliable = ctx.kmax, ctx.kind_of, ctx.unreliable
    xyz = scenario.xyz
    start, end = graph.start, graph.end
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)
    relaxed = critical is not None
    fan = FanBound(G, scenario.n)
    is_v_point = scenario.kind == Kind.V
    options = ctx.options
    fast_legs = getattr(model, "compiled_lengths", None) if options.compiled_legs else None
    # Once numba is loaded (a search before this one needed it) the compiled legs cost
    # nothing to start: from the first label.
    legs_from = -1 if "numba" in sys.modules else options.compiled_legs_from
    # Per (point, critical points visited): the partial routes kept (``_kept``), sorted by
    # length, and their lengths.
    archive: dict[tuple[int, frozenset[int]], tuple[list[float], list[tuple]]] = {}

    probe = origin is not None
    inc = incumbents if incumbents is not None else _Incumbents(kmax)
    prober = None if relaxed else ctx.prober
    probe_labels = 0
    expanded: list[tuple[tuple, tuple]] = []
    if nogoods is None:
        nogoods = {}

    ceiling = ctx.ceiling
    # Straight legs: queue a partial route by its least continuation that no found route
    # dominates (``least_open``), not by its least continuation of all, so that partial routes
    # only the few-corrections end still needs wait until routes there are found, instead of
    # being expanded as soon as their many-corrections continuations look short. Any order
    # exhausts the same queue: the order only decides how soon routes are found.
    by_open = ctx.open_order and relaxed and not probe

    # G2: for this model's legs, or in the search over the pair relaxation, whose cost-to-go
    # it is exactly (never in the heading-free relaxation, whose legs are shorter).
    pairs = ctx.pair_floor if relaxed else ctx.pairs
    pair_floor = ctx.pair_floor

    def by_level(
        length: float,
        k: int,
        j: int,
        states: dict,
        mass: float,
        to_go: np.ndarray | None,
    ) -> bool:
        """Whether found routes cover the partial route, tested per probability level.
        ``to_go``: the label's bound over every continuation (it holds for each level too)."""
        if (relaxed and not probe) or j == start:
            return False
        failures = ctx.failures(labels)  # (a probe's: the probes' labels before it)
        if failures is None and ceiling is None:
            return False
        if failures is None:
            return inc.covers_by_level(length, k, mass, lambda gap: to_go, ceiling)
        memo: dict[tuple[int, ...], np.ndarray | None] = {}

        def bound(gap: float) -> np.ndarray | None:
            key = tuple(failures.forced(w, gap) for w in states.values())
            if key not in memo:
                rows = failures.bound(j, states, gap)
                memo[key] = None if rows is None or to_go is None else _larger(rows, to_go)
            return memo[key]

        return inc.covers_by_level(length, k, mass, bound, ceiling)

    for points in seeds:
        inc.offer(ctx.seed(points))
    if prober is not None:
        for route in inc.found:
            prober.hope(route.points)
    counter = itertools.count()
    # A carries no error and makes no correction: |A - B| bounds every route, whatever its
    # corrections.
    heap: list[_Open] = [
        origin
        or _Open(
            float(graph.to_end[start]),
            next(counter),
            0.0,
            start,
            0,
            {scenario.initial_errors: 1.0},
            heading_a if pair_floor is None else None,  # the pair relaxation: no arc flown yet
            (start,),
            np.array([graph.to_end[start]]),
            -1,
        )
    ]
    labels = 0
    exhausted = True
    escaped: Found | None = None  # a probe's relaxed completion that no incumbent dominates
    while heap:
        entry = heapq.heappop(heap)
        f, _, L, node, k, states, heading, path, to_go, arc = entry
        mass = sum(states.values())
        # Routes found since this label was queued may now cover it.
        if by_open:
            least = inc.least_open(L, k, to_go, mass)
            if least == math.inf:
                continue
            if least > f:  # queued before routes that now cover its shortest continuations
                heapq.heappush(heap, entry._replace(f=least))
                continue
        elif inc.covers(L, k, to_go, mass) or by_level(L, k, node, states, mass, to_go):
            continue
        if prober is not None and node != start and labels >= options.probe_from:
            covered, spent = prober(entry, inc, budget)
            probe_labels += spent
            if covered:
                continue
        if not budget.take():
            heapq.heappush(heap, entry)
            exhausted = False
            break
        labels += 1
        if probe:
            expanded.append((_key(critical, node, path[:-1]), _kept(L, k, states, mass, arc)))
        if budget.due():
            budget.report(labels, len(heap), len(inc.found), f)
        lo, hi = graph.indptr[node], graph.indptr[node + 1]
        targets = graph.target[lo:hi].astype(np.int64)
        straight = graph.length[lo:hi]
        if pair_floor is not None:  # the heading is the arc flown last (None at A)
            flown = straight if heading is None else pair_floor.legs(heading)
            headings = lo + np.arange(hi - lo)
        elif model.carries_heading:
            # Compiled airplane legs once the search proves long (numba loads in a fraction
            # of a second: short searches never pay for it).
            if fast_legs is not None and heading is not None and labels > legs_from:
                flown, headings = fast_legs(xyz[node], heading, xyz[targets])
            else:
                flown, headings = model.lengths(xyz[node], heading, xyz[targets])
        else:  # heading-free legs are as long as the graph's arcs
            flown, headings = straight, None
        v_min = min(s[0] for s in states)
        h_min = min(s[1] for s in states)
        ok = (v_min + flown <= graph.lim_v[targets]) & (h_min + flown <= graph.lim_h[targets])
        inner = np.flatnonzero(ok & (targets != end))
        carried = np.where(is_v_point[targets[inner]], h_min, v_min) + flown[inner]
        rows = fan.rows(targets[inner], carried)
        ok[inner[covered_fan(L + flown[inner], k + 1, rows, inc.best(mass))]] = False
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
                        escaped = Found(nL, k, new_mass, path + (j,))
                        break
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
                    next(counter),
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
        if escaped is not None:
            break
    if probe:
        covered = exhausted and escaped is None
        if covered:  # so is every partial route the probe expanded
            for key, state in expanded:
                nogoods.setdefault(key, []).append(state)
        witness = [] if escaped is None else [escaped]
        return BnbResult(witness, [], covered, labels, time.perf_counter() - t0, exhausted)
    live = []
    # Which open partial routes a found route covers only sharpens the statement's bounds: a
    # search the time limit stopped with hundreds of thousands open spent 25 s past a 60 s
    # limit here. Past the limit plus ``ending_grace`` the rest stay open unexamined: bounds and
    # "optimal" marks only weaker for it, never wrong.
    stop_at = None if budget.deadline is None else budget.deadline + options.ending_grace

    def still_open(e: _Open) -> tuple:  # (f, L, k, bounds to go, mass), as ``_ending`` takes
        return (e.f, e.length, e.corrections, e.to_go, sum(e.states.values()))

    for at, e in enumerate(heap):
        if stop_at is not None and at % 1024 == 0 and work_clock.now() > stop_at:
            live.extend(map(still_open, heap[at:]))
            break
        row = still_open(e)
        _, L, k, to_go, mass = row
        if not inc.covers(L, k, to_go, mass) and not by_level(L, k, e.node, e.states, mass, to_go):
            live.append(row)
    return _ending(ctx, inc, live, labels, t0, exhausted, probe_labels)


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


# The compiled search's leg modes by the model's kernel kind (``search_kernel.LEGS_*``; that
# module is imported only when a search compiles).
_LEGS_MODE = {"airplane": 2, "cs3d": 3}


def _legs_mode(ctx: _Context, critical: frozenset[int] | None) -> int | None:
    """How ``search_kernel`` flies the legs of a search over walks (None: it cannot, the
    search stays in Python): 0 heading-free legs, 1 the pair relaxation's, 2 airplane or 3
    cs3d legs from the heading (``search_kernel.LEGS_*``)."""
    if critical is None or ctx.open_order or not ctx.options.compiled_search:
        return None
    if len(critical) > MAX_COMPILED_CRITICAL:
        return None
    if ctx.pair_floor is not None:
        return 1
    if not ctx.model.carries_heading:
        return 0
    kernel = ctx.model.kernel_legs()
    return None if kernel is None else _LEGS_MODE[kernel.kind]


def _compiled_search(
    ctx: _Context,
    critical: frozenset[int],
    budget: Budget,
    seeds: Sequence[Sequence[int]],
    legs_mode: int,
) -> BnbResult:
    """``_search`` over walks run by ``search_kernel`` (see there), with the same result."""
    t0 = time.perf_counter()
    if "gcs_planner.core.search_kernel" not in sys.modules:
        # Numba compiles the kernel on its first use after installing (about 17 s of CPU on
        # the 2-core test machine, with the expansion it shares with the probes; see
        # docs/benchmarks.md, "The first plan after installing") and loads it from its cache
        # after that.
        budget.setup("the compiled search (compiled once after installing)")
    from gcs_planner.core import search_kernel as sk

    scenario, graph, model = ctx.scenario, ctx.graph, ctx.model
    inc = _Incumbents(ctx.kmax)
    for points in seeds:
        inc.offer(ctx.seed(points))
    bits = np.full(scenario.n, -1, np.int64)
    for b, point in enumerate(sorted(critical)):
        bits[point] = b
    pairs = ctx.pair_floor
    heading_a = scenario.heading_at_a
    kernel = model.kernel_legs() or KernelLegs("none", 0.0, math.inf, math.inf)
    legs = Legs(
        legs_mode,
        np.ascontiguousarray(scenario.xyz, float),
        kernel.radius,
        kernel.tan_climb,
        kernel.tan_descent,
        heading_a is not None,
        np.zeros(3) if heading_a is None else np.asarray(heading_a, float),
        kernel.run_in,
        kernel.run_out,
        *kernel.at_points(scenario.xyz[:, 2]),
    )
    seeded = Seeds(
        np.array([f.length for f in inc.found], float),
        np.array([f.corrections for f in inc.found], np.int64),
        np.array([f.probability for f in inc.found], float),
        np.cumsum([0, *(len(f.points) for f in inc.found)]).astype(np.int64),
        np.array([p for f in inc.found for p in f.points], np.int64),
    )
    limit = -1 if budget.max_labels is None else max(0, budget.max_labels - budget.spent)
    sk._BUDGETS.append(budget)
    try:
        out = sk.search(
            graph.record(
                scenario, ctx.unreliable, ctx.params.p_success, ctx.params.residual_m, ctx.kmax,
                bits,
            ),
            ctx.G.record(),
            NO_PAIRS if pairs is None else pairs.record(),
            legs,
            seeded,
            limit,
        )  # fmt: skip
    finally:
        sk._BUDGETS.pop()
    labels, stopped, f_len, f_k, f_p, f_ptr, f_points, o_f, o_L, o_k, o_mass, o_ptr, o_to_go = out
    budget.stopped(("", "labels", "time")[stopped], int(labels))
    inc = _Incumbents(ctx.kmax)
    for g in range(len(f_len)):
        points = tuple(int(p) for p in f_points[f_ptr[g] : f_ptr[g + 1]])
        inc.add(Found(float(f_len[g]), int(f_k[g]), float(f_p[g]), points))
    live = []
    for x in range(len(o_f)):
        to_go = o_to_go[o_ptr[x] : o_ptr[x + 1]]
        L, k, mass = float(o_L[x]), int(o_k[x]), float(o_mass[x])
        if not inc.covers(L, k, to_go, mass):
            live.append((float(o_f[x]), L, k, to_go, mass))
    return _ending(ctx, inc, live, int(labels), t0, stopped == 0)
