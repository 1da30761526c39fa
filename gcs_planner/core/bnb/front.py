"""The exact Pareto front by branch and bound (``bnb_front``) and the decremental
state-space relaxation that makes dominance over walks exact (``_relaxed``)."""

from __future__ import annotations

import time
from collections.abc import Sequence

from gcs_planner.core.bnb.context import Options, _Context
from gcs_planner.core.bnb.incumbents import BnbResult, Ceiling, _least_length
from gcs_planner.core.bnb.probes import _Prober
from gcs_planner.core.bnb.search import _search
from gcs_planner.core.budget import DEFAULT_MAX_LABELS, Budget
from gcs_planner.core.reach import ReachGraph
from gcs_planner.scenario.model import Scenario


def bnb_front(
    scenario: Scenario,
    *,
    probability: bool,
    max_corrections: int | None = None,
    max_labels: int | None = DEFAULT_MAX_LABELS,
    seeds: Sequence[Sequence[int]] = (),
    dominance: bool = True,
    budget: Budget | None = None,
    graph: ReachGraph | None = None,
    options: Options | None = None,
) -> BnbResult:
    """Exact Pareto front of (length, corrections[, probability]) with the scenario's turning
    radius, by best-first branch and bound. ``probability`` False treats every correction as
    certain (the two-objective model). ``seeds`` are routes known beforehand (for example from
    an easier model): the feasible ones start as incumbents, which only speeds the proof.
    ``dominance`` False keeps whole simple routes even with straight legs (a reference).

    With straight legs a partial route is its point, length, corrections and error-state
    distribution: one that is no better on each of them than another at the same point cannot
    lead anywhere the other cannot, so it is dropped. That ignores where the routes have been,
    so it solves a relaxation over walks; decremental state-space relaxation (as in
    ``search.straight_front``) makes it exact: points that front walks repeat become critical,
    and partial routes that visited different critical points are never compared. With turns
    the heading makes partial routes incomparable, and the search keeps whole simple routes.

    ``budget`` (labels per search, seconds for the whole call, progress) overrides
    ``max_labels``. ``graph``: the scenario's reach graph, when the caller has it already.
    ``options``: how it runs (compiled or Python parts, when it probes; ``Options``), never
    what it finds.
    """
    t0 = time.perf_counter()
    if budget is None:
        budget = Budget(max_labels)
    ctx = _Context(scenario, probability, max_corrections, graph, budget, options)
    if not dominance:
        res = _search(ctx, None, budget.share(stage="search"), seeds)
    elif not ctx.model.carries_heading:
        ctx.open_order = True
        res = _relaxed(ctx, budget.share(stage="search"), seeds)
    else:
        # With turns: first the exact front of the relaxation whose legs are the model's
        # heading-free lower bounds (the chord for cs3d). Every route flown with turns is the
        # same route with those legs made longer and less likely to arrive, so that front bounds
        # each turned front point from below. Then dominance that ignores the
        # heading: no proof, but it finds good routes fast (the certain one, the most reliable
        # ones). Both seed the search over simple routes, whose exhaustion, or gaps, is what is
        # reported.
        floor = _relaxed(ctx.relaxed(), budget.share(0.25, "heading-free floor"), ())
        # With airplane legs (three objectives) a tighter floor: the relaxation that knows the
        # cone of headings at each point (``pair_bounds``), within metres of the front. It
        # keeps more partial routes apart, some 3 to 5 times the labels of the heading-free
        # floor; it is tried when that fits the label budget, and used when it is proven.
        limit = budget.max_labels
        pair_cost = ctx.options.pair_floor_cost * floor.labels
        if ctx.pairs is not None and (limit is None or pair_cost <= limit):
            pair = _relaxed(ctx.pair_relaxed(), budget.share(0.25, "pair floor"), ())
            spent = floor.labels + pair.labels
            if pair.optimal or not floor.optimal:
                floor = pair
            floor.labels = spent
        if floor.optimal and ctx.probability:
            ctx.ceiling = Ceiling(floor.front, ctx.kmax)
        if floor.optimal:
            ctx.prober = _Prober(ctx, floor.critical)
        guide_budget = budget.share(0.25, "heading-free guide")
        guide = _relaxed(ctx, guide_budget, [*seeds, *(f.points for f in floor.front)])
        simple = [f.points for f in guide.front if len(set(f.points)) == len(f.points)]
        res = _search(ctx, None, budget.share(stage="search"), [*seeds, *simple])
        res.labels += guide.labels + floor.labels
        ctx.prober = None
        if floor.optimal:
            res.lower_bounds = [
                max(lb, _least_length(floor.front, g.corrections, g.probability))
                for g, lb in zip(res.front, res.lower_bounds)
            ]
    res.cut = tuple(dict.fromkeys(ctx.cut))  # the floors' copies share the list
    res.seconds = time.perf_counter() - t0
    return res


def _relaxed(ctx: _Context, budget: Budget, seeds: Sequence[Sequence[int]]) -> BnbResult:
    """Dominance over walks, with decremental state-space relaxation until the front routes are
    simple (exact with straight legs)."""
    critical: frozenset[int] = frozenset()
    spent = rounds = 0
    while True:
        rounds += 1
        res = _search(ctx, critical, budget, seeds)
        res.rounds, res.critical = rounds, tuple(sorted(critical))
        spent += res.labels
        repeated = {p for f in res.front for p in f.points if f.points.count(p) > 1}
        if not repeated:
            break
        if not res.exhausted:
            # A budget ended a relaxed round: its walks are no routes, so fall back to the
            # search over simple routes, which is sound at any budget.
            res = _search(ctx, None, budget.share(stage=budget.stage), seeds)
            spent += res.labels
            break
        critical |= repeated
    res.labels = spent  # every round's labels, the fallback's included
    return res
