"""What every round of a branch and bound shares: the graph, the cost-to-go and the other
bounds, the leg model, the seeds flown, and the ``Options`` it searches with."""

from __future__ import annotations

import copy
import itertools
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from gcs_planner.core.bnb.flown import _compiled_flight, flown_route
from gcs_planner.core.bnb.incumbents import Ceiling, Found
from gcs_planner.core.bnb.open_routes import Probe
from gcs_planner.core.budget import Budget
from gcs_planner.core.cost_to_go import cost_to_go
from gcs_planner.core.failure_bounds import FailureBounds, failure_bounds
from gcs_planner.core.pair_bounds import PairBounds, pair_bounds
from gcs_planner.core.probability import success_probability
from gcs_planner.core.reach import ReachGraph, build_reach_graph
from gcs_planner.core.route import Leg, evaluate_route
from gcs_planner.geometry.legs import LegModel, scenario_leg_model
from gcs_planner.runtime.compile_notice import kernel_cached
from gcs_planner.scenario.model import Kind, Scenario


@dataclass(frozen=True)
class Options:
    """How a branch and bound runs, never what it finds: when it makes which bounds and probes,
    and whether its parts run compiled (numba) or in Python, the readable reference the tests
    hold the compiled ones to. Every choice leaves the front exact; the defaults are the
    measured ones (``bnb_front(..., options=Options(...))`` for tests and benchmarks)."""

    # Labels a search over simple routes and its probes spend, per arc of the reach graph,
    # before the failure bounds are made (over the reach graph: their cost-to-go has a copy of
    # each arc per forced failure). A search that proves its front in fewer never pays for
    # them, and on large maps their making costs more than the labels they save.
    failure_bounds_per_arc: float = 1.0
    # How many times the heading-free floor's labels the pair floor is expected to need at most.
    pair_floor_cost: int = 4
    # A probe (``_Prober``) gives up after this many labels: the partial route then stays open.
    probe_labels: int = 1000
    # Labels a search over simple routes expands before it probes: a search that proves its
    # front in fewer never pays for the probes, which on large maps cost more than the search.
    probe_from: int = 200
    # Probes run compiled (``probe_kernel``; False: the Python search), where the critical
    # points fit the kernel's bit masks.
    compiled_probes: bool = True
    # Airplane legs from a heading compiled (``geometry.airplane_kernel``) after this many
    # labels of a search (-1: from the first); False: numpy's throughout.
    compiled_legs: bool = True
    compiled_legs_from: int = 200
    # The searches over walks with turns (floors, guide) compiled (``search_kernel``) when they
    # need more than ``trial`` labels; False: Python throughout.
    compiled_search: bool = True
    trial: int = 300
    # The trial when numba has not compiled the search kernel yet (a fresh install): a search
    # that Python proves within this many labels never compiles it, and the probes stay in
    # Python until the search has compiled: a first plan that Python proves sooner than numba
    # compiles does not wait for the compiler (docs/benchmarks.md, "The first plan after
    # installing"). Chosen by ``Options.first_run``.
    uncached_trial: int = 20_000
    probes_after_search: bool = False
    # Seconds past the time limit a stopped search may spend telling which of its open partial
    # routes a found route covers (``best_first._BestFirst.still_open``).
    ending_grace: float = 2.0


def first_run(options: Options) -> Options:
    """``options`` for a process where numba has not compiled the search kernel and it is not
    loaded: a longer Python trial and Python probes until the search compiles (see
    ``Options.uncached_trial``); ``options`` as given otherwise, or when the environment says
    GCS_PLANNER_COMPILE=always."""
    if "gcs_planner.core.search_kernel" in sys.modules:
        return options
    # A machine that plans often compiles at the first plan that needs the kernels.
    if os.environ.get("GCS_PLANNER_COMPILE", "").lower() == "always":
        return options
    if kernel_cached("gcs_planner.core.search_kernel", "search"):
        return options
    # (The airplane legs' kernel waits as long: importing numba for it alone costs more than
    # it saves in a search that Python finishes.)
    return replace(
        options,
        trial=max(options.trial, options.uncached_trial),
        compiled_legs_from=max(options.compiled_legs_from, options.uncached_trial),
        probes_after_search=True,
    )


class _Context:
    """What every round of the search shares: the graph, the cost-to-go, the model."""

    def __init__(
        self,
        scenario: Scenario,
        probability: bool,
        max_corrections: int | None,
        graph: ReachGraph | None = None,
        budget: Budget | None = None,
        options: Options | None = None,
    ) -> None:
        # The defaults, made for a first run where the kernels are not compiled yet; options
        # given explicitly (tests, benchmarks) are taken as they are.
        self.options = options if options is not None else first_run(Options())
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
        # Set once the floor is proven: the search over simple routes probes with it
        # (``probes._Prober``).
        self.prober: Probe | None = None
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
        labels, ``failure_bounds_per_arc`` per arc of the reach graph: None before (and where
        they do not apply), made on the first call after. The search and its probes count
        their own labels: testing a bound per level costs the search in Python more than
        the compiled probes."""
        if spent < self.options.failure_bounds_per_arc * len(self.graph.target):
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

    def probing(self, failures: Callable[[int], FailureBounds | None]) -> _Context:
        """The context a prober (``_Prober``) searches in: the relaxation that proved the floor
        (the pair relaxation where there are bounds over the cone of arrival headings), with
        this search's ceiling, ``failures`` for its failure bounds (the prober's: they count the
        probes' labels, not the search's) and no prober of its own."""
        probe = self.pair_relaxed() if self.pairs is not None else self.relaxed()
        probe.ceiling = self.ceiling
        probe.failures = failures  # type: ignore[method-assign]
        probe.prober = None
        return probe

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
        lengths = _compiled_flight(
            self.scenario, points, self.model, compiled=self.options.compiled_legs
        )
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
