"""The exact Pareto front of (length, corrections) with straight legs, and why it is empty when
it is: ``straight_search`` finds the front (its docstring has the method), ``diagnose`` says
what rules every route out. The diagnosis searches with ``straight_search`` itself, so the
search leaves the reason to this module rather than importing the diagnosis.
"""

from __future__ import annotations

import math
from dataclasses import replace

from gcs_planner.core.diagnose import why_infeasible
from gcs_planner.core.reach import ReachGraph
from gcs_planner.core.straight_search import (
    FOCUS_GROWTH,
    FOCUS_SLACK,
    FrontPoint,
    FrontResult,
    SearchStats,
    search_front,
)
from gcs_planner.scenario.model import Scenario

__all__ = [
    "FOCUS_GROWTH",
    "FOCUS_SLACK",
    "FrontPoint",
    "FrontResult",
    "SearchStats",
    "straight_front",
]


def straight_front(
    scenario: Scenario,
    graph: ReachGraph | None = None,
    max_corrections: int | None = None,
    compiled: bool | None = None,
    max_rounds: int | None = None,
    focus: bool | None = None,
    upper_bound: float = math.inf,
) -> FrontResult:
    """Exact Pareto front of (length, corrections) over simple feasible routes, straight legs;
    when it is empty, ``why_infeasible`` says why.

    ``compiled``: run the numba kernels (True), numpy (False), or decide by size (None).
    ``max_rounds``: stop the relaxation after this many rounds; the front may then hold walks
    that revisit points, and each of its lengths bounds the simple routes' from below.
    ``focus``: first search only the points that can lie on a front route
    (``straight_search._focused``) and fall back to all of them where that cannot be proven;
    None: when the kernels run and no ``graph`` is given (one that is must be the scenario's
    own reach graph to focus).
    ``upper_bound``: search only the routes no longer than this (the front returned is theirs);
    partial routes that cannot stay within it are dropped from the start.
    """
    res = search_front(scenario, graph, max_corrections, compiled, max_rounds, focus, upper_bound)
    if res.front or res.why_infeasible is not None:
        return res
    # An unbounded search that found nothing, over the graph it searched: diagnose it.
    why = why_infeasible(scenario, res.graph, max_corrections, simple_infeasible=True)
    return replace(res, why_infeasible=why)
