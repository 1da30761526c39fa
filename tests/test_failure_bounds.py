"""The probability-aware bounds of the branch and bound against enumeration: the length still to
fly of a continuation that keeps most of a partial route's mass (``failure_bounds``), and the
relaxation front's floor under every route by corrections and probability (``Ceiling``)."""

from __future__ import annotations

import numpy as np
from test_airplane_legs import climbing_scenario
from test_bnb import all_routes, turning_scenario, uncertain_straight_scenario

from gcs_planner.core.bnb import PROB_EPS, Ceiling, _Context, _relaxed, flown_route
from gcs_planner.core.budget import Budget
from gcs_planner.core.failure_bounds import failure_bounds
from gcs_planner.core.probability import propagate
from gcs_planner.core.reach import build_reach_graph
from gcs_planner.scenario.model import Kind


def scenarios():
    """Straight legs with many unreliable points, turns of several radii, and airplane legs
    with large altitude differences (helices) under several climb limits."""
    for seed in range(20):
        yield uncertain_straight_scenario(seed)
        yield turning_scenario(seed, radius=[200.0, 1500.0, 4000.0][seed % 3])
        yield climbing_scenario(seed)


def prefixes(scenario, points):
    """Per correction point of a route: (position, length so far, error states after it), and
    the route's length and probability, all from the route flown independently."""
    route = flown_route(scenario, points)
    kind = [Kind(int(c)) for c in scenario.kind]
    states = {(0.0, 0.0): 1.0}
    length = 0.0
    out = []
    for i, stop in enumerate(route.stops[1:], start=1):
        leg = stop.leg.length
        if not np.isfinite(leg):
            return [], route.length, 0.0
        j = points[i]
        states, _ = propagate(
            states, leg, kind[j], bool(scenario.unreliable[j]), scenario.params
        )
        length += leg
        if not states:
            return [], route.length, 0.0
        if i < len(points) - 1:
            out.append((i, length, dict(states)))
    return out, length, min(1.0, sum(states.values()))


def test_failure_bounds_never_exceed_a_continuation_that_keeps_that_much_mass() -> None:
    checked = forced = 0
    for scenario in scenarios():
        graph = build_reach_graph(scenario)
        bounds = failure_bounds(scenario, graph)
        if bounds is None:
            continue
        for points in all_routes(scenario):
            steps, total, probability = prefixes(scenario, points)
            if probability <= 0:
                continue
            for i, length, states in steps:
                j = points[i]
                mass = sum(states.values())
                loss = mass - probability
                rest = total - length
                more = len(points) - 2 - i  # corrections after j
                # the tightest gap this continuation satisfies, and looser ones
                for gap in (loss + 1e-7, loss + 0.05, loss + 0.3, mass):
                    if gap <= loss:
                        continue
                    row = bounds.bound(j, states, gap)
                    assert row is not None, (points, i, gap)
                    assert row[min(more, len(row) - 1)] <= rest + 1e-6, (points, i, gap)
                    checked += 1
                    forced += any(bounds.forced(w, gap) > 0 for w in states.values())
    print(checked, forced)
    assert checked >= 1_000 and forced >= 100, (checked, forced)


def test_the_relaxation_front_floors_every_route_by_corrections_and_probability() -> None:
    checked = 0
    for scenario in scenarios():
        if scenario.params.turn_radius <= 0:
            continue
        ctx = _Context(scenario, True, None)
        floor = _relaxed(ctx.relaxed(), Budget(None), ())
        assert floor.optimal
        ceiling = Ceiling(floor.front, ctx.kmax)
        levels = sorted({0.0, *(f.probability for f in floor.front)})
        for points in all_routes(scenario):
            _, length, probability = prefixes(scenario, points)
            if probability <= 0:
                continue
            c = len(points) - 2
            for lo in levels:
                if probability > lo + PROB_EPS:
                    assert ceiling.least_above(lo)[c] <= length + 1e-6, (points, lo)
                    checked += 1
            # nothing is more likely than the relaxation's likeliest route
            assert probability <= max(f.probability for f in floor.front) + PROB_EPS
    print(checked)
    assert checked >= 200, checked
