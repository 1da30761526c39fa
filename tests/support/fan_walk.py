"""The front of every simple route walked depth first as ``enumeration.dfs_front`` walks it, each
prefix's onward legs flown in one call of the leg model's fan (``lengths``: every next point
from the prefix's heading at once) instead of one ``leg`` call per next point: the same legs
(``AirplaneLegs.leg`` flies them with the same ``airplane_legs``), so the same front, for the
reference fronts of the larger scenarios the compiled searches are held against."""

from __future__ import annotations

import numpy as np

from gcs_planner.core.probability import propagate
from gcs_planner.geometry.legs import scenario_leg_model
from gcs_planner.scenario.model import Kind, Scenario

from .enumeration import dfs_front, walked_front


def fanned_dfs_front(scenario: Scenario, probability: bool) -> list[tuple[float, int, float]]:
    """``dfs_front(scenario, probability)``: the Pareto front of (length, corrections,
    -probability) over every simple route, sorted as it sorts them. Scenarios it cannot fan
    (no heading carried, or an envelope per leg) are walked by ``dfs_front`` itself."""
    model = scenario_leg_model(scenario)
    if not getattr(model, "carries_heading", False) or getattr(model, "envelope", None):
        return dfs_front(scenario, probability)
    xyz, params, n = scenario.xyz, scenario.params, scenario.n
    kind = [Kind(int(c)) for c in scenario.kind]
    unreliable = scenario.unreliable if probability else np.zeros(n, dtype=bool)
    heading_a = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a)
    values = []

    def onward(last: int, heading, targets: list[int]) -> list[tuple]:  # noqa: ANN001
        if heading is None:  # a free heading at A: the leg's own rules, one leg at a time
            legs = [model.leg(xyz[last], None, xyz[t]) for t in targets]
            return [(float(leg.length), leg.heading_out) for leg in legs]
        lengths, headings = model.lengths(xyz[last], heading, xyz[targets])
        return [(float(d), headings[x]) for x, d in enumerate(lengths)]

    def extend(path, heading, length, states) -> None:  # noqa: ANN001 - the walk's state
        targets = [t for t in range(n) if t not in path]
        for t, (d, out) in zip(targets, onward(path[-1], heading, targets)):
            if not np.isfinite(d):
                continue
            after, _ = propagate(states, d, kind[t], bool(unreliable[t]), params)
            if not after:
                continue
            if t == scenario.end:
                p = min(1.0, sum(after.values())) if probability else 1.0
                values.append((round(length + d, 6), len(path) - 1, round(-p, 12)))
            else:
                extend((*path, t), out, length + d, after)

    extend((scenario.start,), heading_a, 0.0, {(0.0, 0.0): 1.0})
    return walked_front(values, probability)
