"""Branch and bound over simple routes, for what the layered search cannot carry in a label:
the heading (turns: the flown length of a leg depends on the whole route before it) and the
distribution of error states (uncertain corrections).

Labels are whole partial routes (point, heading, flown length, corrections, error-state
distribution, path), explored best-first by f = L + G_j(e), G the admissible cost-to-go of
``cost_to_go``. A label is pruned when a route already found is at least as good on every
objective it can still reach: length <= f, corrections <= k, probability >= the mass still
alive. When the queue empties, the routes found are exactly the Pareto front under the model —
the proof is the exhausted search. If a label budget stops it earlier, every front point gets
the lower bound that the open labels still allow, and the gap is reported, never hidden.

With turns, partial routes of different headings are incomparable, and the search over whole
simple routes grows too fast where the front spans long routes (dataset 2, three objectives).
So each partial route the search pops is first *probed* (``_Prober``): the exact completions of
it in the relaxation that proved the floor (legs bounded over the cone of headings the route
can arrive with, where partial routes do compare by dominance) are searched, and if every one is
dominated by a route already found, so is every flown completion, and the partial route is
dropped. The states such a probe expanded are covered too and prune later probes (nogoods).
"""

from __future__ import annotations

import bisect
import copy
import heapq
import itertools
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from gcs_planner.core.budget import DEFAULT_MAX_LABELS, Budget
from gcs_planner.core.cost_to_go import cost_to_go
from gcs_planner.core.failure_bounds import FailureBounds, failure_bounds
from gcs_planner.core.kernel_records import NO_PAIRS, Legs, Seeds
from gcs_planner.core.pair_bounds import PairBounds, pair_bounds
from gcs_planner.core.prefilter import FanBound, covered_fan
from gcs_planner.core.probability import propagate, success_probability
from gcs_planner.core.proof import PROB_EPS, lower_bounds, settled
from gcs_planner.core.reach import ReachGraph, build_reach_graph
from gcs_planner.core.route import Leg, Route, evaluate_route
from gcs_planner.geometry.legs import (
    FlownLeg,
    KernelLegs,
    LegModel,
    path_angle_deg,
    scenario_leg_model,
)
from gcs_planner.geometry.trajectory import route_trajectory
from gcs_planner.scenario.model import Kind, Scenario

if TYPE_CHECKING:
    from gcs_planner.core.probe_kernel import CompiledProbes

# Labels a search over simple routes and its probes spend, per arc of the reach graph, before
# the failure bounds are made (over the reach graph: their cost-to-go has a copy of each arc
# per forced failure). A search that proves its front in fewer never pays for them: dataset 2
# with turns proves in about 17,600 probe labels with them, 21,500 without, and made over the
# pairs at the first probe they cost a quarter of its time; on random 1,500 points they cost
# 0.7 s to save 50 labels.
FAILURE_BOUNDS_PER_ARC = 1.0
# How many times the heading-free floor's labels the pair floor is expected to need at most.
PAIR_FLOOR_COST = 4
# A probe (``_Prober``) gives up after this many labels: the partial route then stays open.
PROBE_LABELS = 1000
# Labels a search over simple routes expands before it probes: a search that proves its front
# in fewer never pays for the probes (random 5,000 points, default mode: 4 s, 14 s probing).
PROBE_FROM = 200
# Probes run compiled (``probe_kernel``; False: the Python search below, the reference the
# tests hold them to), where the critical points fit the kernel's bit masks.
COMPILED_PROBES = True
MAX_COMPILED_CRITICAL = 62
# Airplane legs from a heading compiled (``geometry.airplane_kernel``) after this many labels of
# a search; False: numpy's throughout.
COMPILED_LEGS = True
COMPILED_LEGS_FROM = 200
# The searches over walks with turns (floors, guide) compiled (``search_kernel``) when they
# need more than this many labels; False: Python throughout.
COMPILED_SEARCH = True
TRIAL = 300
# Seconds past the time limit a stopped search may spend telling which of its open partial
# routes a found route covers (``_search``'s ending).
ENDING_GRACE = 2.0
# Dominance between error-state distributions asks Hall's condition of at most this many sets
# (``_stochastically_dominates``); beyond, the partial routes are kept apart (always safe).
MAX_UNIONS = 256

__all__ = ["DEFAULT_MAX_LABELS", "PROB_EPS", "BnbResult", "Found", "bnb_front", "flown_route"]


@dataclass(frozen=True)
class Found:
    length: float
    corrections: int
    probability: float
    points: tuple[int, ...]


@dataclass
class BnbResult:
    front: list[Found]
    lower_bounds: list[float]
    optimal: bool
    labels: int
    seconds: float
    exhausted: bool
    # Over the open labels no front point dominates: how many, and the least length they can
    # still reach (inf when there are none: the front is then complete).
    open_labels: int = 0
    open_bound: float = math.inf
    # Straight legs: rounds of decremental state-space relaxation and the critical points.
    rounds: int = 1
    critical: tuple[int, ...] = ()
    # Per front point: whether it is proven to belong to the front *and* no open partial route
    # can still lead to a front route with no more corrections (or, with the probability
    # objective, at least its probability). See ``settled``.
    proven: list[bool] | None = None
    # Labels the probes of this search expanded (``_Prober``).
    probe_labels: int = 0
    # What the time limit cut short or skipped before the search (in words; empty: nothing).
    # Every bound stays admissible without it: only the proof gets harder.
    cut: tuple[str, ...] = ()


def _least_length(front: Sequence[Found], corrections: int, probability: float) -> float:
    """The least length on ``front`` with at most ``corrections`` and at least ``probability``."""
    return min(
        (
            f.length
            for f in front
            if f.corrections <= corrections and f.probability >= probability - PROB_EPS
        ),
        default=math.inf,
    )


def _dominated(found: Sequence[Found], length: float, k: int, prob: float) -> bool:
    """Whether a found route is at least as good as (length, k, prob) on every objective."""
    return _least_length(found, k, prob) <= length


class _Incumbents:
    """The routes found so far, asked one question many times: is every route a partial route
    can still become — (at least L + G_j(e, m) metres, k + m corrections, at most its mass) for
    each m — already matched by a found route?"""

    def __init__(self, kmax: int) -> None:
        self.kmax = kmax
        self.found: list[Found] = []
        # best() per number of found routes at least so likely (which ones: the likeliest).
        self._best: dict[int, np.ndarray] = {}
        self._probabilities: list[float] = []  # the found routes', ascending
        self._levels: list[float] | None = None

    def add(self, new: Found) -> None:
        self.found = [
            g for g in self.found if not _dominated([new], g.length, g.corrections, g.probability)
        ]
        self.found.append(new)
        self._best.clear()
        self._probabilities = sorted(f.probability for f in self.found)
        self._levels = None

    def levels(self) -> list[float]:
        """The found routes' probabilities, largest first, equal ones (within PROB_EPS) once."""
        if self._levels is None:
            levels: list[float] = []
            for p in sorted((f.probability for f in self.found), reverse=True):
                if not levels or p < levels[-1] - PROB_EPS:
                    levels.append(p)
            self._levels = levels
        return self._levels

    def best(self, mass: float) -> np.ndarray:
        """best[c] = the least length of a found route with <= c corrections and a probability
        of at least ``mass`` (inf if none)."""
        likely = len(self.found) - bisect.bisect_left(self._probabilities, mass - PROB_EPS)
        b = self._best.get(likely)
        if b is None:
            b = np.full(self.kmax + 1, np.inf)
            for f in self.found:
                if f.probability >= mass - PROB_EPS and f.corrections <= self.kmax:
                    b[f.corrections] = min(b[f.corrections], f.length)
            np.minimum.accumulate(b, out=b)
            self._best[likely] = b
        return b

    def covers(self, length: float, k: int, to_go: np.ndarray | None, mass: float) -> bool:
        """Whether every completion of a partial route (length L so far, k corrections, the
        bound ``to_go`` = G_j(e, m) per m) is dominated by a found route, or none exists."""
        if to_go is None:
            return True
        m = min(len(to_go), self.kmax - k + 1)
        if m <= 0:
            return True
        return bool((length + to_go[:m] >= self.best(mass)[k : k + m]).all())

    def least_open(self, length: float, k: int, to_go: np.ndarray | None, mass: float) -> float:
        """The least length L + G_j(e, m) over the numbers m of further corrections for which
        ``covers`` fails (inf when it holds): no route this partial route still leads to and
        that no found route dominates is shorter. Found routes only accrue, so the value only
        grows while the partial route waits in the queue."""
        if to_go is None:
            return math.inf
        m = min(len(to_go), self.kmax - k + 1)
        if m <= 0:
            return math.inf
        reach = length + to_go[:m]
        reach = reach[reach < self.best(mass)[k : k + m]]
        return float(reach.min()) if len(reach) else math.inf

    def covers_by_level(
        self,
        length: float,
        k: int,
        mass: float,
        bound: Callable[[float], np.ndarray | None],
        ceiling: Ceiling | None = None,
    ) -> bool:
        """``covers`` with a bound per probability level: ``bound(gap)`` bounds per m the
        continuations that lose less than ``gap`` of the mass (None: there are none), and
        ``ceiling`` bounds the whole length of a route by its corrections and probability.

        A continuation ending with probability pi in (lo, hi] (lo, hi consecutive found
        levels, pi measured with PROB_EPS) is matched only by found routes at least hi likely,
        and it loses less than mass - lo: so each interval is tested with its own bound and its
        own found routes. Above the likeliest found route nothing matches, so a partial route
        that may still end there stays open unless the ceiling rules such routes out."""
        levels = self.levels()
        width = self.kmax - k + 1
        if width <= 0:
            return True
        for hi, lo in zip([None, *levels], [*levels, None]):
            floor = 0.0 if lo is None else lo + PROB_EPS
            if floor >= mass:
                continue  # every continuation ends at most lo + PROB_EPS likely: lower intervals
            to_go = bound(mass - floor)
            if to_go is None:
                continue
            reach = np.empty(width)
            m = min(len(to_go), width)
            reach[:m] = length + to_go[:m]
            reach[m:] = length + to_go[-1]
            if ceiling is not None:
                above = -math.inf if lo is None else lo  # the last interval: every route
                np.maximum(reach, ceiling.least_above(above)[k:], out=reach)
            best = np.full(width, np.inf) if hi is None else self.best(hi)[k:]
            if not (reach >= best).all():
                return False
        return True


class Ceiling:
    """What the exact front of a relaxation says of every route: each route of the model is,
    relaxed, weakly dominated by a point of that front, and relaxing a route shortens it and
    raises its probability. So a route with c corrections and a probability above ``lo`` is at
    least as long as the shortest front point of the relaxation with <= c corrections and a
    probability of at least ``lo`` (inf: no such route)."""

    def __init__(self, front: Sequence[Found], kmax: int) -> None:
        self.front = list(front)
        self.kmax = kmax
        self._least: dict[float, np.ndarray] = {}

    def least_above(self, lo: float) -> np.ndarray:
        """Per number of corrections c = 0..kmax: the least length of a route with c
        corrections whose probability exceeds ``lo`` + PROB_EPS. Probabilities reached in
        different orders differ by far less than PROB_EPS / 2, so a relaxed front point counts
        when it exceeds ``lo`` + PROB_EPS / 2: rounding can only weaken the bound."""
        least = self._least.get(lo)
        if least is None:
            least = np.full(self.kmax + 1, np.inf)
            for f in self.front:
                if f.probability > lo + PROB_EPS / 2 and f.corrections <= self.kmax:
                    least[f.corrections] = min(least[f.corrections], f.length)
            np.minimum.accumulate(least, out=least)
            self._least[lo] = least
        return least


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
    """
    t0 = time.perf_counter()
    if budget is None:
        budget = Budget(max_labels)
    ctx = _Context(scenario, probability, max_corrections, graph, budget)
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
        if ctx.pairs is not None and (limit is None or PAIR_FLOOR_COST * floor.labels <= limit):
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


class _Context:
    """What every round of the search shares: the graph, the cost-to-go, the model."""

    def __init__(
        self,
        scenario: Scenario,
        probability: bool,
        max_corrections: int | None,
        graph: ReachGraph | None = None,
        budget: Budget | None = None,
    ) -> None:
        # The user's budget: once its time limit has passed, the bounds below are cut short or
        # skipped (each only speeds the proof), and ``cut`` says which; meanwhile it shows
        # what the set-up builds.
        self.budget = budget if budget is not None else Budget(None)
        self.cut: list[str] = []
        self.scenario = scenario
        self.probability = probability
        self.params = scenario.params
        self.model: LegModel = scenario_leg_model(scenario)
        self.graph = build_reach_graph(scenario) if graph is None else graph
        self.G = cost_to_go(scenario, self.graph, stop=self._layers("cost-to-go"))
        if self.G.cut_at is not None:
            self.cut.append(_cut_bound("the cost-to-go", self.G.cut_at))
        self.kmax = scenario.n - 2 if max_corrections is None else max_corrections
        self.kind_of = [Kind(int(c)) for c in scenario.kind]  # Enum() is slow in the loop
        self.unreliable = scenario.unreliable if probability else np.zeros(scenario.n, dtype=bool)
        # Bounds that know how much probability a continuation can keep (``failure_bounds``).
        # Only where a label is dear (legs flown from a heading, no dominance): with
        # heading-free legs dominance already keeps the search small and the bounds cost more
        # than they save.
        # Bounds that know the cone of headings a route arrives with (``pair_bounds``); only
        # for this model's own legs, never for its relaxation's.
        # (Two objectives prove fast without them: there they cost more than they save.)
        self.pairs: PairBounds | None = None
        if probability and self.model.carries_heading:
            if self.budget.expired():
                self.cut.append("no bounds over the cone of arrival headings")
            else:
                self.pairs = pair_bounds(
                    scenario, self.graph, self.model, stop=self._layers("bounds over headings")
                )
                if self.pairs is not None and self.pairs.G.cut_at is not None:
                    self.cut.append(
                        _cut_bound("the bound over arrival headings", self.pairs.G.cut_at)
                    )
        # Made once the search has proven long enough to need them (``failures``).
        self._failures: FailureBounds | None = None
        self._failures_made = not (probability and self.model.carries_heading)
        # The proven front of the heading-free relaxation, once known (see ``Ceiling``).
        self.ceiling: Ceiling | None = None
        # Set on the copy that searches the pair relaxation (``pair_relaxed``).
        self.pair_floor: PairBounds | None = None
        # Set once the floor is proven: the search over simple routes probes with it.
        self.prober: _Prober | None = None
        # Queue partial routes by their least open continuation (``_search``): set for the
        # straight-leg search, whose floors and probes (turns) keep the plain order.
        self.open_order = False
        # Seeds flown so far (``seed``), shared with the relaxations' copies.
        self._seeds: dict[tuple, Found | None] = {}

    def _layers(self, what: str) -> Callable[[], bool]:
        """A cost-to-go's ``stop``: asked before each layer, it shows the layer and says
        whether the time limit has passed."""
        layer = itertools.count()

        def stop() -> bool:
            self.budget.setup(f"{what}, layer {next(layer)}")
            return self.budget.expired()

        return stop

    def failures(self, spent: int) -> FailureBounds | None:
        """The failure bounds (``failure_bounds``) for what asks once it has spent ``spent``
        labels, FAILURE_BOUNDS_PER_ARC per arc of the reach graph: None before (and where
        they do not apply), made on the first call after. The search and its probes count
        their own labels: testing a bound per level costs the search in Python more than
        the compiled probes."""
        if spent < FAILURE_BOUNDS_PER_ARC * len(self.graph.target):
            return None
        if not self._failures_made:
            self._failures_made = True
            name = "bounds per probability level"
            if self.budget.expired():
                self.cut.append(f"no {name}")
            else:
                self._failures = failure_bounds(self.scenario, self.graph, stop=self._layers(name))
                if self._failures is not None and self._failures.G.cut_at is not None:
                    self.cut.append(_cut_bound(f"the {name}", self._failures.G.cut_at))
        return self._failures

    def relaxed(self) -> _Context:
        """The same search over the heading-free relaxation of the leg model (each leg as long
        as its lower bound). The reach graph and the cost-to-go are made of those bounds
        already: shared, not built again."""
        other = copy.copy(self)
        other.model = self.model.relaxation()
        other.pairs = None
        other.pair_floor = None
        return other

    def pair_relaxed(self) -> _Context:
        """The search over the relaxation whose leg j -> t after i -> j is lb(i, j, t), the least
        over the cone of headings a route from i arrives at j with (``pair_bounds``). Partial
        routes that came to j from the same i continue alike: they compare by dominance."""
        other = self.relaxed()
        other.pair_floor = self.pairs
        return other

    def seed(self, points: Sequence[int]) -> Found | None:
        """A known route as an incumbent, evaluated under this search's model (once per model
        and route: the floors' routes seed the guide, the guide's the search, the rounds of a
        relaxation the same ones again)."""
        points = tuple(int(i) for i in points)
        key = (self.model, self.probability, points)
        if key not in self._seeds:
            self._seeds[key] = self._flown_seed(points)
        return self._seeds[key]

    def _flown_seed(self, points: tuple[int, ...]) -> Found | None:
        lengths = _compiled_flight(self.scenario, points, self.model)
        if lengths is None:
            route = flown_route(self.scenario, points, self.model)
        else:
            R = self.scenario.params.turn_radius
            route = evaluate_route(self.scenario, points, [Leg(d) for d in lengths], turn_radius=R)
        if not route.feasible:
            return None
        prob = 1.0
        if self.probability:
            legs = [s.leg for s in route.stops[1:]]
            prob = success_probability(self.scenario, points, legs).probability
        return Found(route.length, route.corrections, min(1.0, prob), points) if prob > 0 else None


def _cut_bound(name: str, cut_at: int) -> str:
    """What a cost-to-go cut short (``cut_at``) still knows, in words."""
    if cut_at == 0:
        return f"{name}: no layer made, only the straight distance to B"
    return f"{name}: exact up to {cut_at - 1} further corrections, the distance to B beyond"


class _Prober:
    """Whether a partial route of the search over simple routes can still lead anywhere, asked
    of the relaxation that proved the floor: the exact relaxed completions of the partial route,
    searched with dominance, each compared with the routes found so far.

    Relaxing a completion only shortens its legs and raises its probability, and the partial
    route's own past is exact (its length, corrections and error states): so if every relaxed
    completion is dominated by a found route, every flown one is too, and the partial route is
    covered. The relaxation's search is small where the simple routes' search is not: partial
    routes at one point that came by one arc compare by dominance there (``pair_relaxed``)."""

    def __init__(self, ctx: _Context, critical: Sequence[int]) -> None:
        probe = ctx.pair_relaxed() if ctx.pairs is not None else ctx.relaxed()
        probe.ceiling = ctx.ceiling
        # The same bounds, made once: once the probes before (not the search) have spent
        # enough, so that a probe, compiled or not, has them throughout or not at all.
        self.root = ctx
        self.spent = 0  # labels of the probes so far
        probe.failures = self.failures  # type: ignore[method-assign]
        probe.prober = None
        self.ctx = probe
        # Walks that revisit none of these points: the floor's, under which it was exact.
        self.critical = frozenset(critical)
        # The probes compiled (``probe_kernel``): the same answers, made on first need (numba
        # is loaded only by searches that probe).
        self.compiled: CompiledProbes | None = None
        self._compile = COMPILED_PROBES and len(self.critical) <= MAX_COMPILED_CRITICAL
        # Partial routes of the relaxation proven covered, by ``_key``; the found routes only
        # grow, so they stay covered.
        self.nogoods: dict[tuple, list[tuple]] = {}
        # Prefixes of relaxed completions that escaped a probe, and of the routes the search
        # starts with: a partial route along one is likely to escape too (its own relaxed
        # completion is no longer than the route and at least as likely), so it is expanded
        # unprobed (skipping a probe is always sound).
        self.hopeful: set[tuple[int, ...]] = set()

    def failures(self, _spent: int = 0) -> FailureBounds | None:
        """The search's failure bounds for a probe, by the labels of the probes before it (a
        probe's own labels do not count: it has them throughout or not at all)."""
        return self.root.failures(self.spent)

    def hope(self, points: Sequence[int], after: int = 1) -> None:
        """Mark the prefixes of ``points`` longer than ``after`` points (not the whole route)
        hopeful."""
        points = tuple(points)
        self.hopeful.update(points[:n] for n in range(after + 1, len(points)))

    def __call__(self, entry: _Open, inc: _Incumbents, budget: Budget) -> tuple[bool, int]:
        """(covered, labels spent) for the heap ``entry`` of the search whose routes are
        ``inc``."""
        f, _, L, node, k, states, _heading, path, to_go, arc = entry
        if path in self.hopeful:
            return False, 0
        if self._compile:
            if self.compiled is None:
                # Numba compiles the kernel on its first use after installing (20 to 30 s on a
                # 2-core machine) and loads it from its cache after that.
                budget.setup("the compiled probes (compiled once after installing)")
                from gcs_planner.core.probe_kernel import CompiledProbes

                self.compiled = CompiledProbes(self.ctx, self.critical)
            child = budget.probe(PROBE_LABELS)
            limit = 0 if child.expired() else PROBE_LABELS
            covered, labels, escape = self.compiled(
                inc, L, node, k, states, arc, path, to_go, limit
            )
            self.spent += labels
            if escape:
                self.hope(path + escape, after=len(path))
            return covered, labels
        key = _key(self.critical, node, path[:-1])
        state = _kept(L, k, states, sum(states.values()), arc)
        if _dominated_by(self.nogoods.get(key, ()), state, self.ctx.pair_floor):
            return True, 0
        # The pair relaxation's heading is the arc flown last.
        first = arc if self.ctx.pair_floor is not None else None
        origin = _Open(f, 0, L, node, k, states, first, path, to_go, arc)
        res = _search(
            self.ctx,
            self.critical,
            budget.probe(PROBE_LABELS),
            (),
            origin=origin,
            incumbents=inc,
            nogoods=self.nogoods,
        )
        self.spent += res.labels
        for w in res.front:
            self.hope(w.points, after=len(path))
        return res.optimal, res.labels


def _key(critical: frozenset[int] | None, j: int, before: tuple[int, ...]) -> tuple:
    """Where a partial route at j that visited ``before`` is compared with others: j and the
    critical points it visited (their revisits are barred)."""
    return (j, frozenset(critical.intersection(before)) if critical else frozenset())


def _pair_margin(pairs: PairBounds | None, kept: int, new: int) -> float:
    """How much longer the next leg can be for a partial route that came to j by arc ``kept``
    than for one that came by arc ``new``, in the pair relaxation (0 without it). Only the
    next leg depends on the arc (lb(i, j, t)); every leg after it is lb(j, t, u) for both. So
    a partial route that is this much shorter, with errors this much smaller, than another
    at j continues no worse whatever it does: its next leg is at most this much longer, every
    later one the same."""
    if pairs is None or kept == new:
        return 0.0
    return pairs.margin(kept, new)


def _kept(L: float, k: int, states: dict, mass: float, arc: int) -> tuple:
    """A partial route as the dominance tests keep it: (L, k, error states, mass, arc flown
    last, least vertical error, least horizontal error)."""
    return (L, k, states, mass, arc, min(v for v, _ in states), min(h for _, h in states))


def _dominated_by(
    kept: Sequence[tuple], state: tuple, pairs: PairBounds | None, upto: int | None = None
) -> bool:
    """Whether a partial route at a point, ``state`` (``_kept``), continues no better than one
    of ``kept`` (at the same point, having visited the same critical points) whatever it does
    next, in a relaxation whose legs depend on the arc flown last only through ``pairs``
    (``_pair_margin``). ``upto``: only the first so many of ``kept`` are asked (those no
    longer than ``state`` when ``kept`` is sorted by length: no longer one dominates)."""
    L, k, states, mass, arc, v, h = state
    for aL, ak, ast, am, a_arc, av, ah in itertools.islice(kept, upto):
        # The cheap tests first; the least errors of a dominating distribution are no larger.
        if aL > L or ak > k or am < mass - PROB_EPS or av > v or ah > h:
            continue
        shift = _pair_margin(pairs, a_arc, arc)
        if (
            aL + shift <= L
            and av + shift <= v
            and ah + shift <= h
            and _stochastically_dominates(_shifted(ast, shift), states)
        ):
            return True
    return False


def _shifted(states: dict, shift: float) -> dict:
    """Error states with ``shift`` metres more on both components."""
    if shift == 0.0:
        return states
    return {(v + shift, h + shift): m for (v, h), m in states.items()}


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


def _larger(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The pointwise larger of two bounds per m (each carried on with its last entry)."""
    if len(a) == len(b):
        return np.maximum(a, b)
    width = max(len(a), len(b))
    out = np.empty(width)
    out[: len(a)] = a
    out[len(a) :] = a[-1]
    other = np.empty(width)
    other[: len(b)] = b
    other[len(b) :] = b[-1]
    return np.maximum(out, other, out=out)


def _stochastically_dominates(d1: dict, d2: dict) -> bool:
    """Whether every continuation succeeds at least as often from the error-state distribution
    ``d1`` as from ``d2``. Success from a state only falls as either error grows, so this holds
    when d2's mass can be moved, unit by unit, onto d1's states no worse in both components:
    by Hall's theorem, when every set S of d2's states weighs no more than d1's states lying
    below some state of S. Where more than MAX_UNIONS sets would have to be asked (only with
    more than 8 states in d2), the two are not compared (False is always safe)."""
    if len(d1) == 1:  # one state: it must lie below every state of d2 and weigh as much
        (((v1, h1), m1),) = d1.items()
        return all(v1 <= v2 and h1 <= h2 for v2, h2 in d2) and m1 >= sum(d2.values()) - PROB_EPS
    if len(d2) == 1:  # one state: the states of d1 below it must weigh as much
        (((v2, h2), m2),) = d2.items()
        return sum(m for (v1, h1), m in d1.items() if v1 <= v2 and h1 <= h2) >= m2 - PROB_EPS
    weights = list(d1.values())
    # Per state of d2: the set (a bit mask) of d1's states below it, and its mass.
    below: list[tuple[int, float]] = []
    for (v2, h2), m2 in d2.items():
        bits = 0
        for i, (v1, h1) in enumerate(d1):
            if v1 <= v2 and h1 <= h2:
                bits |= 1 << i
        if not bits:
            return False
        below.append((bits, m2))
    # Hall's condition need only be asked of the sets S closed under "below": for a union R of
    # masks, of all of d2's states whose masks lie within R. Any other S with the same reach R
    # is a subset of that one and needs no more. The unions are few where the masks nest.
    unions = {0}
    for bits in {b for b, _ in below}:
        unions |= {u | bits for u in unions}
        if len(unions) > MAX_UNIONS:
            return False
    unions.discard(0)
    for reach in unions:
        need = sum(m2 for bits, m2 in below if bits | reach == reach)
        have = sum(w for i, w in enumerate(weights) if reach >> i & 1)
        if need > have + PROB_EPS:
            return False
    return True


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
    it once it needs more than TRIAL labels)."""
    legs_mode = None if origin is not None or not compiled else _legs_mode(ctx, critical)
    left = None if budget.max_labels is None else budget.max_labels - budget.spent
    if legs_mode is not None and critical is not None:
        if "gcs_planner.core.search_kernel" in sys.modules:  # loaded: no trial needed
            return _compiled_search(ctx, critical, budget, seeds, legs_mode)
    if legs_mode is not None and critical is not None and (left is None or left > TRIAL):
        # Compiled once the search proves long: a short one never loads numba. The trial is
        # the same search, so starting over loses nothing but its time.
        trial_budget = budget.probe(TRIAL)
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
    fast_legs = getattr(model, "compiled_lengths", None) if COMPILED_LEGS else None
    # Once numba is loaded (a search before this one needed it) the compiled legs cost
    # nothing to start: from the first label.
    legs_from = -1 if "numba" in sys.modules else COMPILED_LEGS_FROM
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
        seed = ctx.seed(points)
        if seed is not None and not _dominated(
            inc.found, seed.length, seed.corrections, seed.probability
        ):
            inc.add(seed)
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
            {(0.0, 0.0): 1.0},
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
        if prober is not None and node != start and labels >= PROBE_FROM:
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
    # limit here. Past the limit plus ENDING_GRACE the rest stay open unexamined: bounds and
    # "optimal" marks only weaker for it, never wrong.
    stop_at = None if budget.deadline is None else budget.deadline + ENDING_GRACE

    def still_open(e: _Open) -> tuple:  # (f, L, k, bounds to go, mass), as ``_ending`` takes
        return (e.f, e.length, e.corrections, e.to_go, sum(e.states.values()))

    for at, e in enumerate(heap):
        if stop_at is not None and at % 1024 == 0 and time.monotonic() > stop_at:
            live.extend(map(still_open, heap[at:]))
            break
        row = still_open(e)
        _, L, k, to_go, mass = row
        if not inc.covers(L, k, to_go, mass) and not by_level(
            L, k, e.node, e.states, mass, to_go
        ):
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
    if critical is None or ctx.open_order or not COMPILED_SEARCH:
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
        # Numba compiles the kernel on its first use after installing (20 to 30 s on a
        # 2-core machine) and loads it from its cache after that.
        budget.setup("the compiled search (compiled once after installing)")
    from gcs_planner.core import search_kernel as sk

    scenario, graph, model = ctx.scenario, ctx.graph, ctx.model
    inc = _Incumbents(ctx.kmax)
    for points in seeds:
        seed = ctx.seed(points)
        if seed is not None and not _dominated(
            inc.found, seed.length, seed.corrections, seed.probability
        ):
            inc.add(seed)
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


def flown_route(
    scenario: Scenario, points: tuple[int, ...], model: LegModel | None = None
) -> Route:
    """Re-evaluate a route under the scenario's leg model (or ``model``), independently of the
    search: every leg flown again from the heading the previous one ended with."""
    R = scenario.params.turn_radius
    if model is not None and model.name == "bound":
        xyz = scenario.xyz[list(points)]
        bounds = [float(model.lower_bounds(a, b[None, :])[0]) for a, b in zip(xyz, xyz[1:])]
        return evaluate_route(scenario, points, [Leg(d) for d in bounds], turn_radius=R)
    legs = [flown_leg(leg) for leg in flown_route_legs(scenario, points, model)]
    return evaluate_route(scenario, points, legs, turn_radius=R)


def flown_route_legs(
    scenario: Scenario, points: tuple[int, ...], model: LegModel | None = None
) -> tuple[FlownLeg, ...]:
    """The legs of a route flown under the scenario's leg model (or ``model``), from the
    heading at A (free when none is given)."""
    heading = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)
    model = scenario_leg_model(scenario) if model is None else model
    R = scenario.params.turn_radius
    return route_trajectory(scenario.xyz[list(points)], R, heading, model).legs


def _compiled_flight(
    scenario: Scenario, points: tuple[int, ...], model: LegModel
) -> list[float] | None:
    """The flown length of each leg of a route as ``flown_route`` flies it, the legs after the
    first with the model's compiled legs (within a few ulp; about 3 µs a leg instead of about
    260); None where that would load numba (only once a search has loaded it) or the
    model has no compiled legs. The first leg is ``flown_route``'s own (a free heading at A
    has its own rules), the heading carried from it."""
    fast = getattr(model, "compiled_lengths", None) if COMPILED_LEGS else None
    if fast is None or "numba" not in sys.modules or len(points) < 3:
        return None
    xyz = scenario.xyz
    first = flown_route_legs(scenario, points[:2], model)[0]
    lengths = [first.length if first.reachable else math.inf]
    # (As ``route_trajectory``: after a leg that cannot be flown, the heading it started with.)
    heading = np.asarray(first.heading_out if first.reachable else first.heading_in, float)
    for a, b in zip(points[1:], points[2:]):
        flown, headings = fast(xyz[a], heading, xyz[b][None, :])
        lengths.append(float(flown[0]))
        if math.isfinite(flown[0]):
            heading = headings[0]
    return lengths


def flown_leg(leg: FlownLeg) -> Leg:
    """The route table's view of a flown leg."""
    return Leg(
        leg.length,
        leg.arc_length,
        leg.arc_angle,
        int(getattr(leg, "helix_turns", 0)),
        path_angle_deg(leg),
    )
