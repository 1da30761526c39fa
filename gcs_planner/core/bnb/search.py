"""One best-first search of the branch and bound (``_search``): in Python (``best_first``) or
compiled (``search_kernel``), and the compiled one's ending (``ending._ending`` for both)."""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Sequence

import numpy as np

from gcs_planner.core.bnb.best_first import _BestFirst
from gcs_planner.core.bnb.context import _Context
from gcs_planner.core.bnb.ending import _ending
from gcs_planner.core.bnb.incumbents import BnbResult, Found, _Incumbents
from gcs_planner.core.bnb.open_routes import _Open
from gcs_planner.core.budget import Budget
from gcs_planner.core.kernel_records import NO_PAIRS, Legs, Seeds
from gcs_planner.geometry.legs import KernelLegs

# Critical points the compiled search and probes carry as bits of a mask.
MAX_COMPILED_CRITICAL = 62


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
    it once it needs more than ``Options.trial`` labels). The Python search's steps are
    ``best_first._BestFirst``'s."""
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
    search = _BestFirst(ctx, critical, budget, origin, incumbents, nogoods)
    search.start(seeds)
    search.run()
    if search.probe:
        return search.probe_result()
    live = search.still_open()
    return _ending(
        ctx, search.inc, live, search.labels, search.t0, search.exhausted, search.probe_labels
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
