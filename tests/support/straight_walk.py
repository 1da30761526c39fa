"""The front of every simple route with straight legs, walked depth first: the same values as
``enumeration.enumerate_straight_front`` (lengths from the coordinates, the exact chain of
``probability.propagate`` from the scenario's initial errors), each prefix's chain computed once
for all its extensions instead of once per route."""

from __future__ import annotations

import numpy as np

from gcs_planner.core.probability import propagate
from gcs_planner.scenario.model import Kind, Scenario

from .enumeration import pareto


def walked_straight_front(scenario: Scenario) -> list[tuple[float, int, float]]:
    """(length, corrections, -probability) of the routes that can arrive, Pareto-filtered and
    sorted as ``enumerate_straight_front`` does. A prefix is dropped only when no mass is left
    after it (every extension then arrives with probability 0, which that front leaves out)."""
    xyz, n, params = scenario.xyz, scenario.n, scenario.params
    # Leg lengths as enumerate_straight_front takes them (norms of coordinate differences),
    # added from A onwards, as its sum of fewer than 8 legs adds them.
    chord = np.linalg.norm(xyz[None, :, :] - xyz[:, None, :], axis=2)
    kind = [Kind(int(c)) for c in scenario.kind]
    unreliable = [bool(u) for u in scenario.unreliable]
    values: list[tuple[float, int, float]] = []

    def extend(path: tuple[int, ...], length: float, states: dict) -> None:
        last = path[-1]
        for t in range(n):
            if t in path:
                continue
            leg = float(chord[last, t])
            after, arrived = propagate(states, leg, kind[t], unreliable[t], params)
            if t == scenario.end:
                p = min(1.0, arrived)
                if p > 0:
                    values.append((round(length + leg, 6), len(path) - 1, round(-p, 12)))
            elif after:
                extend((*path, t), length + leg, after)

    extend((scenario.start,), 0.0, {scenario.initial_errors: 1.0})
    return pareto(values)
