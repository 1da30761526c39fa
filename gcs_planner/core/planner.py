"""From a scenario to a Plan: the front of the chosen objectives and one route chosen from it.

Which search runs follows from the model: straight legs (turn radius 0) use the exact layered
search; turns and the probability objective use the branch and bound of ``bnb``. Each says
whether its front is proven optimal.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from gcs_planner.core.bnb import DEFAULT_MAX_LABELS, PROB_EPS, bnb_front, flown_route
from gcs_planner.core.choose import choose as choose_route
from gcs_planner.core.probability import success_probability
from gcs_planner.core.route import Route, evaluate_route
from gcs_planner.core.search import straight_front
from gcs_planner.errors import InfeasibleError
from gcs_planner.policy import DEFAULT_MIN_PROBABILITY, choose_index, default_objectives
from gcs_planner.scenario.model import Scenario

OBJECTIVES = ("length", "corrections", "probability")


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
    max_labels: int = DEFAULT_MAX_LABELS,
    min_probability: float = DEFAULT_MIN_PROBABILITY,
) -> Plan:
    """Plan a scenario. Raises InfeasibleError (with the reason) when no route exists.

    ``objectives`` None: the policy's (:func:`gcs_planner.policy.default_objectives`). The route
    is chosen among the front routes at least ``min_probability`` likely to arrive; when none
    is, the most reliable one is chosen and ``threshold_met`` is False. The front is reported
    whole either way."""
    if not 0.0 <= min_probability <= 1.0:
        raise ValueError(f"min_probability must be within [0, 1], not {min_probability}")
    objectives = default_objectives(scenario, objectives, choice)
    for o in objectives:
        if o not in OBJECTIVES:
            raise ValueError(f"unknown objective {o!r}")
    use_probability = "probability" in objectives
    radius = scenario.params.turn_radius
    if use_probability or radius > 0:
        result = _branch_and_bound(scenario, use_probability, max_corrections, max_labels)
    else:
        result = _straight(scenario, max_corrections)
    routes, lower_bounds, optimal, statement, stats = result
    if not routes:
        raise InfeasibleError(f"{scenario.name}: {statement}")
    order = sorted(range(len(routes)), key=lambda i: (routes[i].corrections, routes[i].length))
    routes = [routes[i] for i in order]
    lower_bounds = [lower_bounds[i] for i in order]
    # Every route's probability is exact (re-evaluated), whichever objectives were searched.
    chosen, threshold_met = choose_index(
        routes,
        choice=choice,
        weights=weights,
        min_probability=min_probability,
        use_probability=use_probability,
    )
    return Plan(
        scenario,
        tuple(routes),
        chosen,
        choice,
        objectives,
        optimal,
        statement,
        tuple(lower_bounds),
        stats,
        min_probability,
        threshold_met,
    )


def _straight(scenario: Scenario, max_corrections: int | None):
    res = straight_front(scenario, max_corrections=max_corrections)
    stats = {
        "search_seconds": res.stats.seconds,
        "graph_seconds": res.stats.graph_seconds,
        "labels": res.stats.labels,
        "arcs": res.stats.arcs,
        "relaxation_rounds": res.stats.rounds,
        "critical_points": len(res.stats.critical),
    }
    if not res.front:
        return [], [], True, res.why_infeasible, stats
    routes = [_with_probability(scenario, evaluate_route(scenario, fp.points)) for fp in res.front]
    statement = (
        "exact: the Pareto front of (length, corrections) over all simple feasible routes with "
        "straight legs (label search with dominance and bounds, elementarity by decremental "
        "state-space relaxation)"
    )
    return routes, [r.length for r in routes], True, statement, stats


def _with_probability(scenario: Scenario, route: Route) -> Route:
    """Attach the exact success probability (1 when the route uses no unreliable point)."""
    legs = [s.leg for s in route.stops[1:]]
    sp = success_probability(scenario, route.points, legs)
    return route.with_probabilities(sp.probability, sp.per_stop)


def _branch_and_bound(
    scenario: Scenario, use_probability: bool, max_corrections: int | None, max_labels: int
):
    res = bnb_front(
        scenario,
        probability=use_probability,
        max_corrections=max_corrections,
        max_labels=max_labels,
    )
    stats = {
        "search_seconds": res.seconds,
        "labels": res.labels,
        "open_labels": res.open_labels,
        "relaxation_rounds": res.rounds,
        "critical_points": len(res.critical),
    }
    radius = scenario.params.turn_radius
    model = (
        f"turning radius {radius:g} m (3D Dubins CS legs)" if radius > 0 else "straight legs"
    ) + (", uncertain corrections" if use_probability else "")
    if not res.front:
        if res.optimal:
            return [], [], True, f"no feasible route with {model} (exhaustive search)", stats
        return (
            [],
            [],
            False,
            (
                f"no feasible route found with {model} within the search budget of "
                f"{max_labels} labels ({res.open_labels} partial routes left open)"
            ),
            stats,
        )
    # Every reported route is re-evaluated from scratch: its flown length, errors and
    # probability come from the route, not from the search's labels.
    routes = [_with_probability(scenario, flown_route(scenario, g.points)) for g in res.front]
    if res.optimal:
        how = (
            "dominance on length, corrections and error-state distribution, made exact over "
            "simple routes by decremental state-space relaxation"
            if radius == 0
            else "over whole simple routes (headings make partial routes incomparable)"
        )
        statement = (
            f"exact: the Pareto front over all simple feasible routes with {model}, proven by "
            f"exhaustive branch and bound ({res.labels} labels; bound: straight-leg cost-to-go "
            f"per number of further corrections; {how})"
        )
    else:
        statement = (
            f"not proven within the budget of {max_labels} labels per search: each route's "
            f"gap to its proven lower bound (from the open partial routes and the exact "
            f"straight-leg front) is given; routes missing from this front are at least "
            f"{res.open_bound:,.1f} m long"
        )
    return routes, res.lower_bounds, res.optimal, statement, stats
