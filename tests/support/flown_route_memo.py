"""Routes flown once per test module for the enumerations that several tests repeat over the
same scenarios: ``core.bnb.flown_route``'s legs remembered by the scenario's contents and the
points before them.

The enumerations (support/enumeration.py) are the reference the searches are compared with;
flying every route of the same seeded scenarios again in each test is most of their CPU. A
scenario made again from the same seed has the same contents, so it meets the routes flown for
it before; any other scenario (other limits, ``with_params``) is flown afresh."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from gcs_planner.core.route import Route
from gcs_planner.scenario.model import Scenario

from .prefix_flight import PrefixFlights


def contents(value: object) -> object:
    """``value`` as a hashable whole: arrays by their type, shape and bytes, dataclasses field
    by field (but their private caches), sequences and mappings item by item, the rest by its
    repr (a float's repr is exact)."""
    if isinstance(value, np.ndarray):
        return ("array", value.dtype.str, value.shape, value.tobytes())
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return (type(value).__qualname__,) + tuple(
            (f.name, contents(getattr(value, f.name)))
            for f in dataclasses.fields(value)
            if not f.name.startswith("_")
        )
    if isinstance(value, (tuple, list)):
        return tuple(contents(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((repr(k), contents(v)) for k, v in value.items()))
    return repr(value)


def remembered_flown_route() -> Callable[[Scenario, tuple[int, ...]], Route]:
    """``flown_route`` with a memory of the legs it flew, per scenario, each leg once for every
    route sharing the partial route before it (support/prefix_flight.py).

    A scenario is found by its identity before its contents: hashing a scenario's contents on
    every route flown costs about as much as flying the route from its remembered prefix. A
    scenario object met again is the one whose contents were taken (it is held here, so its id
    is never reused meanwhile); another object with the same contents (a scenario made again
    from the same seed) meets the routes flown for the first."""
    by_contents: dict[object, PrefixFlights] = {}
    by_identity: dict[int, tuple[Scenario, PrefixFlights]] = {}

    def fly(scenario: Scenario, points) -> Route:  # noqa: ANN001 - any sequence of indices
        held = by_identity.get(id(scenario))
        if held is None or held[0] is not scenario:
            key = contents(scenario)
            if key not in by_contents:
                by_contents[key] = PrefixFlights(scenario)
            held = (scenario, by_contents[key])
            by_identity[id(scenario)] = held
        return held[1].route(tuple(int(p) for p in points))

    return fly


def remember_flown_routes(*modules: object) -> Iterator[None]:
    """For a module-scoped fixture: ``flown_route`` remembered in each of ``modules`` (where
    the callers look it up) until the fixture ends."""
    fly = remembered_flown_route()
    with pytest.MonkeyPatch.context() as patch:
        for module in modules:
            patch.setattr(module, "flown_route", fly)
        yield
