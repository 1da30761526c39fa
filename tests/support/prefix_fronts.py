"""``enumeration.enumerate_front`` of a scenario for both objective sets from one flight of its
simple routes, each flown by prefix (support/prefix_flight.py, the same Route as
``flown_route``), kept per process under the caller's name for the scenario, so that the tests
that ask for both fronts of the same scenarios fly its routes once."""

from __future__ import annotations

from collections.abc import Hashable

from gcs_planner.core.bnb import Options
from gcs_planner.scenario.model import Scenario

from .enumeration import assert_front_equals_enumeration, enumerate_front
from .prefix_flight import every_route_flown

_FRONTS: dict[Hashable, dict[bool, list[tuple]]] = {}


def prefix_front(scenario: Scenario, probability: bool, question: Hashable) -> list[tuple]:
    """``enumerate_front(scenario, probability)``; ``question`` names the scenario (the same
    question must always build the same scenario): both fronts are kept under it."""
    fronts = _FRONTS.get(question)
    if fronts is None:
        flights = list(every_route_flown(scenario))
        fronts = _FRONTS[question] = {
            p: enumerate_front(scenario, p, flights=flights) for p in (False, True)
        }
    return fronts[probability]


def assert_front_equals_prefix_enumeration(
    scenario: Scenario,
    probability: bool,
    question: Hashable,
    options: Options | None = None,
) -> tuple:
    """``enumeration.assert_front_equals_enumeration`` against ``prefix_front``; returns (the
    search's result, the enumerated front)."""
    want = prefix_front(scenario, probability, question)
    return assert_front_equals_enumeration(scenario, probability, question, options, want)
