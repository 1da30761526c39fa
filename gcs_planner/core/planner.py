"""From a scenario to a Plan: the front of the chosen objectives and one route chosen from it.

Which search runs follows from the model: straight legs (turn radius 0) use the exact layered
search; turns and the probability objective use the branch and bound of ``bnb``. Each says
whether its front is proven optimal.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

from gcs_planner.core.bnb import DEFAULT_MAX_LABELS, PROB_EPS, bnb_front, flown_route
from gcs_planner.core.budget import DEFAULT_TIME_LIMIT, Budget, ProgressCallback
from gcs_planner.core.choose import DEFAULT_MIN_PROBABILITY, choose_index, default_objectives
from gcs_planner.core.choose import choose as choose_route
from gcs_planner.core.diagnose import why_infeasible
from gcs_planner.core.focus import focus, large
from gcs_planner.core.probability import success_probability
from gcs_planner.core.reach import build_reach_graph
from gcs_planner.core.route import Route
from gcs_planner.core.search import straight_front
from gcs_planner.core.seeding import certain_front, reliable_seeds
from gcs_planner.errors import InfeasibleError
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Scenario

OBJECTIVES = ("length", "corrections", "probability")


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


@dataclass(frozen=True)
class Plan:
    """The answer to a scenario: the Pareto front, one chosen route, and how sure we are."""

    scenario: Scenario
    routes: tuple[Route, ...]  # the front, sorted by corrections then length
    chosen: int
    choice: str
    objectives: tuple[str, ...]
    optimal: bool
    statement: str
    lower_bounds: tuple[float, ...]  # per route: a proven lower bound on its front value
    stats: dict = field(default_factory=dict)
    # The choice was made among the front routes at least this likely to arrive ...
    min_probability: float = 0.0
    # ... unless none was: then the most reliable route is chosen and this is False.
    threshold_met: bool = True
    # What the user must know about flying these routes: an assumed unlimited climb and the
    # steepest leg, or legs steeper than the aircraft's limits (planned with cs3d or straight).
    warnings: tuple[str, ...] = ()
    # Per route: proven on the front, and no route with no more corrections (nor, with the
    # probability objective, at least its probability) left unexplored. Empty: every route is.
    settled: tuple[bool, ...] = ()

    def proven(self) -> tuple[bool, ...]:
        """Per route, whether its "optimal" flag holds: settled and with no gap."""
        flags = self.settled or (True,) * len(self.routes)
        return tuple(s and gap <= 1e-6 for s, gap in zip(flags, self.gaps()))

    @property
    def front(self) -> tuple[Route, ...]:
        """The Pareto front's routes (sorted by corrections, then length)."""
        return self.routes

    @property
    def route(self) -> Route:
        return self.routes[self.chosen]

    def gaps(self) -> tuple[float, ...]:
        return tuple(max(0.0, r.length - lb) for r, lb in zip(self.routes, self.lower_bounds))

    @property
    def shortest_certain(self) -> int | None:
        """Index of the shortest route that arrives with probability 1 (fewest corrections on a
        tie), None when the front has none."""
        certain = [i for i, r in enumerate(self.routes) if r.probability >= 1.0 - PROB_EPS]
        return min(
            certain, key=lambda i: (self.routes[i].length, self.routes[i].corrections), default=None
        )

    @property
    def most_reliable(self) -> int:
        """Index of the route most likely to arrive (the shortest, then fewest corrections, of
        those)."""
        return choose_route(
            [r.length for r in self.routes],
            [r.corrections for r in self.routes],
            [r.probability for r in self.routes],
            "most-reliable",
        )


def plan(
    scenario: Scenario,
    *,
    objectives: Sequence[str] | None = None,
    choice: str = "compromise",
    weights: Sequence[float] | None = None,
    max_corrections: int | None = None,
    max_labels: int | None = DEFAULT_MAX_LABELS,
    min_probability: float = DEFAULT_MIN_PROBABILITY,
    time_limit: float | None = DEFAULT_TIME_LIMIT,
    progress: ProgressCallback | None = None,
) -> Plan:
    """Plan a scenario. Raises InfeasibleError (with the reason) when no route exists.

    ``objectives`` None: the policy's (:func:`gcs_planner.core.choose.default_objectives`). The
    route
    is chosen among the front routes at least ``min_probability`` likely to arrive; when none
    is, the most reliable one is chosen and ``threshold_met`` is False. The front is reported
    whole either way.

    The budget of the branch and bound (turns, probability): ``max_labels`` per search (None:
    unlimited) and ``time_limit`` seconds in all (None: unlimited); ``progress`` is called
    with a :class:`~gcs_planner.core.budget.Progress` about twice a second meanwhile. When the
    budget ends the search, the plan says what is proven (``optimal`` False, per-route gaps)."""
    if not 0.0 <= min_probability <= 1.0:
        raise ValueError(f"min_probability must be within [0, 1], not {min_probability}")
    objectives = default_objectives(scenario, objectives, choice)
    for o in objectives:
        if o not in OBJECTIVES:
            raise ValueError(f"unknown objective {o!r}")
    if not objectives or len(set(objectives)) != len(objectives):
        raise ValueError(f"objectives must be distinct names, at least one (got {objectives})")
    if max_corrections is not None and max_corrections < 0:
        raise ValueError(f"max_corrections must be >= 0, not {max_corrections}")
    use_probability = "probability" in objectives
    # The layered straight search starts from rest; a state mid-flight (errors at A, see
    # core/from_state.py) is planned by the branch and bound, whose first label carries them.
    if use_probability or scenario_leg_model(scenario).carries_heading or not scenario.from_rest:
        budget = Budget(max_labels, time_limit, progress)
        result = _branch_and_bound(scenario, use_probability, max_corrections, budget)
    else:
        result = _straight(scenario, max_corrections)
    if not result.routes:
        raise InfeasibleError(f"{scenario.name}: {result.statement}")
    found = result.routes
    settled = result.settled or [True] * len(found)
    # The engines search length and corrections (and probability): over fewer objectives the
    # routes another one matches or beats in all of them are not on that front.
    kept = _front_over(found, objectives)
    statement = result.statement
    if len(kept) < len(found):
        dropped = len(found) - len(kept)
        statement += (
            f"; reported over {', '.join(objectives)} only: {dropped} route"
            f"{'' if dropped == 1 else 's'} of the front over "
            f"{', '.join(_SEARCHED[use_probability])} matched or beaten in "
            f"{'it' if len(objectives) == 1 else 'them'} left out"
        )
    order = sorted(kept, key=lambda i: (found[i].corrections, found[i].length))
    routes = [found[i] for i in order]
    # Every route's probability is exact (re-evaluated), whichever objectives were searched.
    chosen, threshold_met = choose_index(
        routes,
        choice=choice,
        weights=weights,
        min_probability=min_probability,
        use_probability=use_probability,
    )
    return Plan(
        scenario=scenario,
        routes=tuple(routes),
        chosen=chosen,
        choice=choice,
        objectives=objectives,
        optimal=result.optimal,
        statement=statement,
        lower_bounds=tuple(result.lower_bounds[i] for i in order),
        stats=result.stats,
        min_probability=min_probability,
        threshold_met=threshold_met,
        warnings=climb_warnings(scenario, routes),
        settled=tuple(bool(settled[i]) for i in order),
    )


# The objectives each engine's front is over, without and with the probability objective.
_SEARCHED = {False: ("length", "corrections"), True: OBJECTIVES}
# Lengths within this many metres are the same length (the legs are flown in floating point).
_LENGTH_TIE_M = 1e-6


def _front_over(routes: Sequence[Route], objectives: Sequence[str]) -> list[int]:
    """Indices of the routes no other route beats in ``objectives`` (at least as good in each
    of them and better in one); of routes tied in all of them, the one best in length, then
    corrections, then probability. On the engines' front over more objectives this is the front
    over these: every value the smaller front reaches is reached there. Over all the searched
    objectives the front is returned as it is."""
    wanted = set(objectives)
    if wanted >= {"length", "corrections"}:
        return list(range(len(routes)))

    def covers(a: Route, b: Route) -> bool:  # a is at least as good as b in every objective
        return (
            ("length" not in wanted or a.length <= b.length + _LENGTH_TIE_M)
            and ("corrections" not in wanted or a.corrections <= b.corrections)
            and ("probability" not in wanted or a.probability >= b.probability - PROB_EPS)
        )

    def beats(a: Route, b: Route) -> bool:
        return covers(a, b) and not covers(b, a)

    best_first = sorted(
        range(len(routes)),
        key=lambda i: (routes[i].length, routes[i].corrections, -routes[i].probability),
    )
    kept: list[int] = []
    for i in best_first:
        if any(beats(r, routes[i]) for r in routes):
            continue
        if any(covers(routes[j], routes[i]) for j in kept):
            continue  # tied in every objective with a route kept: the better one stays
        kept.append(i)
    return sorted(kept)


def climb_warnings(scenario: Scenario, routes: Sequence[Route]) -> tuple[str, ...]:
    """Say what the plan assumed of the climb, and name every leg the aircraft cannot fly."""
    v = scenario.vehicle
    steep: list[tuple[float, int, str, str]] = []  # (|angle|, route, from, to)
    over: list[str] = []
    for k, route in enumerate(routes):
        for prev, stop in zip(route.stops, route.stops[1:]):
            angle = stop.leg.path_angle if stop.leg else 0.0
            steep.append((abs(angle), k, prev.id, stop.id))
            limit = v.max_climb_angle if angle > 0 else v.max_descent_angle
            if stop.leg is not None and stop.leg.angle_limit is not None:
                # an airplane leg's own limit (its highest point's when the envelope is derived
                # per leg)
                limit = stop.leg.angle_limit
            if abs(angle) > limit + 1e-6:
                what = "climbs" if angle > 0 else "descends"
                over.append(f"route {k} leg {prev.id}->{stop.id} {what} at {abs(angle):.1f} deg")
    if not steep:
        return ()
    worst = max(steep)
    if not v.climb_limited:
        return (
            "assumed unlimited climb and descent (90 deg, the contest's model): give "
            "--max-climb-angle/--max-descent-angle or [vehicle] limits; steepest leg: "
            f"route {worst[1]} {worst[2]}->{worst[3]} at {worst[0]:.1f} deg",
        )
    if over:
        limits = f"climb {v.max_climb_angle:g} deg, descent {v.max_descent_angle:g} deg"
        model = "straight" if v.turn_radius <= 0 else v.leg_model
        return (
            f"{len(over)} leg(s) are steeper than the aircraft's limits ({limits}); {model} "
            "legs plan without them and the aircraft cannot fly these: " + "; ".join(over),
        )
    return ()


def _straight(scenario: Scenario, max_corrections: int | None) -> EngineResult:
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


def _branch_and_bound(
    scenario: Scenario, use_probability: bool, max_corrections: int | None, budget: Budget
) -> EngineResult:
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
    heading_free = not scenario_leg_model(scenario).carries_heading
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
    settled = None if res.proven is None else list(res.proven)
    return EngineResult(
        routes=routes,
        lower_bounds=res.lower_bounds,
        optimal=res.optimal,
        statement=statement,
        stats=stats,
        settled=settled,
    )
