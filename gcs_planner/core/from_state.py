"""Planning from a state mid-flight (docs/model.md, "Contingency policies").

After a failed fix the aircraft is at a correction point with a heading, carrying errors, and
has flown some points already (a route stays simple). The continuation it needs is a route from
that state to B: the same problem as a mission's, over the scenario without the points flown,
from a start that is that point, with that heading and those errors. :func:`state_scenario`
states it so, and every search plans it unchanged: the errors at A are
``Scenario.initial_errors`` (the search's first label, the route tables and the probability
start from them), the heading is ``Scenario.heading_at_a`` as for any mission with a given
heading at A.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from gcs_planner.errors import GcsPlannerError
from gcs_planner.scenario.model import Kind, Scenario


@dataclass(frozen=True)
class FlightState:
    """Where the aircraft is and what it carries: at scenario point ``point`` (its fix, if any,
    already applied or failed), flying ``heading`` (a unit vector, or None for any heading),
    with errors ``v``, ``h`` in metres flown since the last vertical / horizontal reset, and
    the scenario points it has flown (A among them)."""

    point: int
    heading: tuple[float, float, float] | None
    v: float
    h: float
    visited: frozenset[int]


def compass_heading(degrees: float) -> tuple[float, float, float]:
    """A horizontal unit vector in the scenario frame (x east, y north) from a compass heading
    (0 north, 90 east)."""
    rad = math.radians(degrees)
    return (math.sin(rad), math.cos(rad), 0.0)


def state_scenario(scenario: Scenario, state: FlightState) -> tuple[Scenario, np.ndarray]:
    """The scenario whose routes are the continuations from ``state``, and the original index of
    each of its points (its routes map back by ``indices[route.points]``).

    Its A is ``state.point`` (kind A, so no fix is made there again), its points are the
    scenario's less those flown; B stays. Raises GcsPlannerError when the state is not one a
    route can be in."""
    n = scenario.n
    at = int(state.point)
    if not 0 <= at < n:
        raise GcsPlannerError(f"state point index {at} is not a point of {scenario.name}")
    kind = Kind(int(scenario.kind[at]))
    if kind == Kind.B:
        raise GcsPlannerError(f"the state is at B ({scenario.ids[at]}): nothing left to plan")
    visited = {int(i) for i in state.visited} | {scenario.start}
    if scenario.end in visited:
        raise GcsPlannerError("the points flown include B")
    for i in visited:
        if not 0 <= i < n:
            raise GcsPlannerError(f"flown point index {i} is not a point of {scenario.name}")
    for name, value in (("vertical", state.v), ("horizontal", state.h)):
        if not (math.isfinite(value) and value >= 0.0):
            raise GcsPlannerError(f"the state's {name} error must be finite and >= 0, not {value}")
    keep = np.array([i for i in range(n) if i == at or i not in visited], dtype=np.int64)
    sub = scenario.subset(keep)
    position = int(np.flatnonzero(keep == at)[0])
    kinds = sub.kind.copy()
    kinds[position] = Kind.A
    unreliable = sub.unreliable.copy()
    unreliable[position] = False
    heading = None
    if state.heading is not None:
        vec = np.asarray(state.heading, dtype=float)
        norm = float(np.linalg.norm(vec))
        if vec.shape != (3,) or not math.isfinite(norm) or norm <= 0.0:
            raise GcsPlannerError(
                f"the state's heading must be a nonzero 3-vector: {state.heading}"
            )
        heading = tuple(float(c) for c in vec / norm)
    out = replace(
        sub,
        kind=kinds,
        unreliable=unreliable,
        heading_at_a=heading,
        initial_errors=(float(state.v), float(state.h)),
        name=f"{scenario.name} from {scenario.ids[at]}",
    )
    return out, keep


def original_points(indices: np.ndarray, points: Iterable[int]) -> tuple[int, ...]:
    """A route of a state's scenario in the original scenario's indices."""
    return tuple(int(indices[int(p)]) for p in points)
