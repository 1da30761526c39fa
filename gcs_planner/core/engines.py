"""The two search engines as the planner runs them, each giving its front flown again from the
routes' points and a statement of what is proven: the layered search for straight legs from
rest (``straight_engine``, ``search.straight_front``) and the branch and bound for turns, the
probability objective or a state mid-flight (``bnb_engine``, ``bnb.bnb_front``, with its
seeds, floor and focus)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from gcs_planner.core.bnb import BnbResult, bnb_front, flown_route
from gcs_planner.core.budget import Budget
from gcs_planner.core.diagnose import why_infeasible
from gcs_planner.core.focus import focus, large
from gcs_planner.core.probability import success_probability
from gcs_planner.core.reach import ReachGraph, build_reach_graph
from gcs_planner.core.route import Route
from gcs_planner.core.search import straight_front
from gcs_planner.core.seeding import certain_front, reliable_seeds
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Scenario


@dataclass
class EngineResult:
    """What a search engine gives the planner: the layered label search (straight legs,
    ``search.straight_front``) or the branch and bound (turns, the probability objective,
    ``bnb.bnb_front``). Its routes are flown again from their points, independently of the
    search's labels."""

    routes: list[Route]  # the front, in the engine's order (empty: no route)
    lower_bounds: list[float]  # per route: a proven lower bound on its front value
    optimal: bool  # the front is proven (or, with no route, infeasibility is)
    statement: str  # what is proven and how, in words (why there is no route when none)
    stats: dict  # the search's figures (``Plan.stats``)
    # Per route: settled (see ``Plan.settled``); None: every route is.
    settled: list[bool] | None = None


def straight_engine(scenario: Scenario, max_corrections: int | None) -> EngineResult:
    """The exact front of (length, corrections) with straight legs (``search.straight_front``),
    its routes flown under the scenario's leg model."""
    res = straight_front(scenario, max_corrections=max_corrections)
    stats = {
        "search_seconds": res.stats.seconds,
        "graph_seconds": res.stats.graph_seconds,
        "labels": res.stats.labels,
        "arcs": res.stats.arcs,
        # Fewer than the scenario's points when the search was focused on the ellipsoid that
        # holds every front route.
        "points": res.stats.points,
        "relaxation_rounds": res.stats.rounds,
        "critical_points": len(res.stats.critical),
    }
    if not res.front:
        model = scenario.vehicle.describe()
        why = f"no feasible route with {model} (exhaustive search): {res.why_infeasible}"
        return EngineResult([], [], True, why, stats)
    # Flown under the scenario's leg model (with R = 0 and climb limits, each leg's path angle
    # and the limits' say on it), independently of the search's labels.
    routes = [_with_probability(scenario, flown_route(scenario, fp.points)) for fp in res.front]
    v = scenario.vehicle
    # With R = 0 the airplane model's climb limits rule too-steep legs out: say they held.
    legs = "straight legs"
    if v.climb_limited and scenario.leg_model == "airplane":
        legs += f" within climb {v.max_climb_angle:g} deg and descent {v.max_descent_angle:g} deg"
    statement = (
        f"exact: the Pareto front of (length, corrections) over all simple feasible routes with "
        f"{legs} (label search with dominance and bounds, elementarity by decremental "
        "state-space relaxation)"
    )
    return EngineResult(
        routes=routes,
        lower_bounds=[r.length for r in routes],
        optimal=True,
        statement=statement,
        stats=stats,
    )


def _with_probability(scenario: Scenario, route: Route) -> Route:
    """Attach the exact success probability (1 when the route uses no unreliable point)."""
    legs = [s.leg for s in route.stops[1:]]
    sp = success_probability(scenario, route.points, legs)
    return route.with_probabilities(sp.probability, sp.per_stop)


def _cut_text(cut: Sequence[str]) -> str:
    """What the time limit cut short before the search, for a statement ('' if nothing)."""
    if not cut:
        return ""
    return f"; the time limit also cut the set-up short ({'; '.join(cut)})"


def bnb_engine(
    scenario: Scenario, use_probability: bool, max_corrections: int | None, budget: Budget
) -> EngineResult:
    """The front by branch and bound (``bnb.bnb_front``), within ``budget``: what it proves,
    or the gaps it leaves, in words."""
    res, searched, graph, inside = _bnb_search(scenario, use_probability, max_corrections, budget)
    stats = {
        "search_seconds": res.seconds,
        "labels": res.labels,
        "open_labels": res.open_labels,
        # Routes missing from an unproven front are at least this long (None: none is missing;
        # JSON has no inf).
        "open_bound": res.open_bound if math.isfinite(res.open_bound) else None,
        "relaxation_rounds": res.rounds,
        # Labels the probes expanded (turns): outside the label budget, within the time limit.
        "probe_labels": res.probe_labels,
        "critical_points": len(res.critical),
        # What the time limit cut short before the search (empty: nothing).
        "setup_cut": list(res.cut),
        # Fewer than the scenario's points when the search was focused (``focus``).
        "points": searched.n,
    }
    model = scenario.vehicle.describe() + (", uncertain corrections" if use_probability else "")
    if not res.front:
        if res.optimal:
            # The reason, from the scenario the search ran over (its points keep their ids).
            why = why_infeasible(
                searched,
                graph,
                max_corrections,
                probability=use_probability,
            )
            why = f"no feasible route with {model} (exhaustive search): {why}"
            return EngineResult([], [], True, why, stats)
        unproven = (
            f"no feasible route found with {model} within the search budget of "
            f"{budget.describe()} ({res.open_labels} partial routes left open), so "
            f"infeasibility is not proven: {budget.advice()}{_cut_text(res.cut)}"
        )
        return EngineResult([], [], False, unproven, stats)
    # Every reported route is re-evaluated from scratch: its flown length, errors and
    # probability come from the route, not from the search's labels.
    routes = [_with_probability(scenario, flown_route(scenario, g.points)) for g in res.front]
    statement = _bnb_statement(scenario, res, budget, model, use_probability, inside)
    settled = None if res.proven is None else list(res.proven)
    return EngineResult(
        routes=routes,
        lower_bounds=res.lower_bounds,
        optimal=res.optimal,
        statement=statement,
        stats=stats,
        settled=settled,
    )


def _bnb_search(
    scenario: Scenario, use_probability: bool, max_corrections: int | None, budget: Budget
) -> tuple[BnbResult, Scenario, ReachGraph, np.ndarray | None]:
    """The branch and bound's result in ``scenario``'s indices, with the scenario and reach
    graph it searched (a subset of the points when focused on the ones ``inside``)."""
    # With the probability objective, the two-objective straight-leg front seeds the search
    # (its fewest-corrections end first of all) and bounds each route from below; the front
    # without the unreliable points seeds it with routes certain to arrive (``seeding``). On
    # large maps it is made with two objectives too: a route of it may bound every front route
    # and focus the search (``focus``). One reach graph for all; on large maps (seconds to
    # build on 20,000 points) it is made only if the search cannot be focused.
    on_large_map = large(scenario)
    graph = None if on_large_map else build_reach_graph(scenario)
    certain, seeds = None, ()
    if use_probability or on_large_map:
        # (The certain front stays whatever the time limit: it is the floor every gap is
        # measured from, and seconds even on 20,000 points. The routes certain to arrive only
        # speed the proof: past the limit they are left out.)
        budget.setup("the two-objective front")
        certain = certain_front(scenario, max_corrections, graph)
        graph = certain.graph if graph is None else graph
        seeds = certain.seeds
        if use_probability:
            budget.setup("routes certain to arrive")
            reliable = () if budget.expired() else reliable_seeds(scenario, max_corrections)
            seeds = (*seeds, *reliable)
    inside = focus(scenario, certain, seeds, use_probability)
    searched = scenario
    if inside is not None:
        # Every front route lies within the ellipsoid (``focus``): search its points alone,
        # in their own indices, and map the routes back.
        budget.setup(f"the {len(inside):,} points a front route can pass")
        searched = scenario.subset(inside)
        graph = build_reach_graph(searched)
        position = {int(p): i for i, p in enumerate(inside)}
        seeds = tuple(tuple(position[p] for p in s) for s in seeds if all(p in position for p in s))
    elif graph is None:
        budget.setup("the reach graph")
        graph = build_reach_graph(scenario)
    res = bnb_front(
        searched,
        probability=use_probability,
        max_corrections=max_corrections,
        budget=budget,
        seeds=seeds,
        graph=graph,
    )
    if inside is not None:
        res.front = [replace(g, points=tuple(int(inside[i]) for i in g.points)) for g in res.front]
    if certain is not None:
        res.lower_bounds = [
            max(lb, certain.floor(g.corrections)) for g, lb in zip(res.front, res.lower_bounds)
        ]
    return res, searched, graph, inside


def _bnb_statement(
    scenario: Scenario,
    res: BnbResult,
    budget: Budget,
    model: str,
    use_probability: bool,
    inside: np.ndarray | None,
) -> str:
    """What the branch and bound proved of its front (or the gaps it left), in words."""
    heading_free = not scenario_leg_model(scenario).carries_heading
    if res.optimal:
        how = (
            "dominance on length, corrections and error-state distribution, made exact over "
            "simple routes by decremental state-space relaxation"
            if heading_free
            else (
                "over whole simple routes (headings make partial routes incomparable), each "
                "partial route dropped once every completion of it in the floor's relaxation is "
                "dominated by a route found"
            )
        )
        bound = "heading-free cost-to-go per number of further corrections"
        if use_probability and not heading_free:
            if scenario_leg_model(scenario).turns_in_bounds:
                bound += " (for airplane legs also over the cone of arrival headings)"
            bound += ", tested per probability level"
        statement = (
            f"exact: the Pareto front over all simple feasible routes with {model}, proven by "
            f"exhaustive branch and bound ({res.labels} labels; bound: {bound}; {how})"
        )
        if inside is not None:
            statement += (
                f"; searched over the {len(inside):,} of {scenario.n:,} points within the "
                "ellipsoid that a route with the fewest corrections bounds"
            )
    else:
        unsettled = len(res.front) - sum(res.proven or ())
        statement = (
            f"not proven within the budget of {budget.describe()} ({budget.advice()}): each "
            f"route's gap to its proven lower bound (from the open partial routes and the "
            f"exact front of the heading-free relaxation) is given; routes missing from this "
            f"front are at least "
            f"{res.open_bound:,.1f} m long; {unsettled} of {len(res.front)} routes are not "
            f"marked optimal because partial routes that may lead to front routes with no "
            f"more corrections (or a higher probability) are still open{_cut_text(res.cut)}"
        )
    return statement
