"""``enumeration.enumerate_front`` of a scenario for both objective sets from one pass over its
simple routes, each flown by prefix (support/prefix_flight.py, the same Route as
``flown_route``), kept per process under the caller's name for the scenario, so that the tests
that ask for both fronts of the same scenarios fly its routes once."""

from __future__ import annotations

from collections.abc import Hashable

import numpy as np

from gcs_planner.core.bnb import Options, bnb_front
from gcs_planner.core.probability import success_probability
from gcs_planner.scenario.model import Scenario

from .enumeration import pareto
from .prefix_flight import every_route_flown

_FRONTS: dict[Hashable, dict[bool, list[tuple]]] = {}


def both_fronts(scenario: Scenario) -> dict[bool, list[tuple]]:
    """``{probability: enumerate_front(scenario, probability)}`` for False and True: a route
    counts when it is feasible (two objectives) or arrives with a positive probability (three)."""
    values: dict[bool, list[tuple]] = {False: [], True: []}
    for points, route in every_route_flown(scenario):
        legs = [s.leg for s in route.stops[1:]]
        p = success_probability(scenario, points, legs).probability
        if p > 0:
            values[True].append((round(route.length, 6), route.corrections, round(-p, 12)))
        if route.feasible:
            values[False].append((round(route.length, 6), route.corrections, 0.0))
    return {probability: pareto(v) for probability, v in values.items()}


def prefix_front(scenario: Scenario, probability: bool, question: Hashable) -> list[tuple]:
    """``enumerate_front(scenario, probability)``; ``question`` names the scenario (the same
    question must always build the same scenario): both fronts are kept under it."""
    fronts = _FRONTS.get(question)
    if fronts is None:
        fronts = _FRONTS[question] = both_fronts(scenario)
    return fronts[probability]


def assert_front_equals_prefix_enumeration(
    scenario: Scenario,
    probability: bool,
    question: Hashable,
    options: Options | None = None,
) -> tuple:
    """``enumeration.assert_front_equals_enumeration`` against ``prefix_front``: the branch and
    bound's front, proven, equal to enumeration of every simple route; returns (the search's
    result, the enumerated front)."""
    result = bnb_front(scenario, probability=probability, max_labels=10**6, options=options)
    assert result.optimal, question
    got = [
        (round(f.length, 6), f.corrections, round(-f.probability, 12) if probability else 0.0)
        for f in result.front
    ]
    want = prefix_front(scenario, probability, question)
    assert [g[1:] for g in got] == [w[1:] for w in want], question
    np.testing.assert_allclose(
        [g[0] for g in got], [w[0] for w in want], atol=1e-6, err_msg=str(question)
    )
    return result, want
