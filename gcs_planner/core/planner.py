"""From a scenario to a Plan: the front of the chosen objectives and one route chosen from it.

Which search runs follows from the model: straight legs (turn radius 0) use the exact layered
search; turns and the probability objective use the branch and bound of ``bnb`` (``engines``
runs either). Each says whether its front is proven optimal.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from gcs_planner.core.bnb import DEFAULT_MAX_LABELS, PROB_EPS
from gcs_planner.core.budget import DEFAULT_TIME_LIMIT, Budget, ProgressCallback
from gcs_planner.core.capture_front import captures_fit
from gcs_planner.core.choose import DEFAULT_MIN_PROBABILITY, choose_index, default_objectives
from gcs_planner.core.choose import choose as choose_route
from gcs_planner.core.constrained_front import within_constraints
from gcs_planner.core.endurance_front import endurance_limit
from gcs_planner.core.engines import EngineResult, bnb_engine, straight_engine
from gcs_planner.core.route import Route
from gcs_planner.errors import InfeasibleError
from gcs_planner.geometry.legs import scenario_leg_model
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

    # One budget for the whole plan: the engine's search and the constrained front's share
    # its CPU seconds, so ``time_limit`` bounds the plan (each search its own labels).
    budget = Budget(max_labels, time_limit, progress)

    # The layered straight search starts from rest; a state mid-flight (errors at A, see
    # core/from_state.py) is planned by the branch and bound, whose first label carries them.
    def run_engine() -> EngineResult:
        turns = scenario_leg_model(scenario).carries_heading
        if use_probability or turns or not scenario.from_rest:
            return bnb_engine(scenario, use_probability, max_corrections, budget)
        return straight_engine(scenario, max_corrections)

    # Constraints the engines do not carry (core/constrained_front.py): the endurance, the
    # captures in a design turbulence. The front of all routes first; the search only when a
    # route of it breaks one.
    constraints = [c for c in (endurance_limit(scenario), captures_fit(scenario)) if c]
    if constraints:
        result = within_constraints(
            scenario, run_engine, constraints, use_probability, max_corrections, budget
        )
    else:
        result = run_engine()
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
