"""One continuation plan per failure state, whichever route reaches it (core/replan.py,
``search_continuation``): ``plan --policy`` replans every route of the front, and the routes
share their first points, so their failure states recur from route to route."""

from __future__ import annotations

import numpy as np
from support.scenarios import contingency_scenario

from gcs_planner.core import planner
from gcs_planner.core.bnb import flown_route
from gcs_planner.core.contingency import evaluate
from gcs_planner.core.replan import replan_on_failure, search_continuation
from gcs_planner.scenario.model import Kind


def test_routes_sharing_their_start_plan_each_failure_state_once(monkeypatch):
    calls: list[str] = []
    real_plan = planner.plan

    def counted(scenario, **kw):
        calls.append(scenario.name)
        return real_plan(scenario, **kw)

    monkeypatch.setattr(planner, "plan", counted)
    checked = 0
    for seed in range(40):
        sc = contingency_scenario(seed, 0.0, n_max=6)
        unreliable = [j for j in range(sc.n) if sc.unreliable[j] and sc.kind[j] in (Kind.V, Kind.H)]
        others = [j for j in range(sc.n) if sc.kind[j] in (Kind.V, Kind.H) and j not in unreliable]
        if not unreliable or len(others) < 2:
            continue
        # Two routes through the same unreliable point first, then apart.
        first = (sc.start, unreliable[0])
        routes = [flown_route(sc, (*first, j, sc.end)) for j in others[:2]]
        shared = search_continuation(sc)
        calls.clear()
        together = [replan_on_failure(sc, r, continuation=shared) for r in routes]
        planned_together = len(calls)
        calls.clear()
        apart = [replan_on_failure(sc, r, continuation=search_continuation(sc)) for r in routes]
        planned_apart = len(calls)
        if planned_apart == 0:
            continue  # lost before the shared point: no failure state to plan from
        # The same policies, found with fewer plans: the state after the first failure is one.
        for a, b in zip(together, apart, strict=True):
            va, vb = evaluate(sc, a.policy), evaluate(sc, b.policy)
            assert np.isclose(va.probability, vb.probability, atol=1e-12)
            assert np.isclose(va.length, vb.length, rtol=1e-12)
        assert planned_together < planned_apart, seed
        checked += 1
    assert checked >= 5
