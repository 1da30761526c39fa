"""Random contingency policies: well-formed trees of simple segments that branch at the points
where a correction can fail."""

from __future__ import annotations

import numpy as np

from gcs_planner.core.contingency import Policy
from gcs_planner.scenario.model import Kind, Scenario


def can_fail_at(sc: Scenario, j: int) -> bool:
    """Whether a correction at point ``j`` can fail: an unreliable V or H point."""
    return bool(sc.unreliable[j]) and int(sc.kind[j]) in (Kind.V, Kind.H)


def random_policy(sc: Scenario, rng: np.random.Generator) -> Policy:
    """A random well-formed policy: random simple segments, branching at unreliable points."""
    corr = [j for j in range(sc.n) if int(sc.kind[j]) in (Kind.V, Kind.H)]

    def node(at: int, visited: set[int]) -> Policy:
        pts = [at]
        while True:
            free = [j for j in corr if j not in visited]
            if not free or rng.random() < 0.3:
                pts.append(sc.end)
                return Policy(tuple(pts))
            j = int(rng.choice(free))
            pts.append(j)
            visited = visited | {j}
            if can_fail_at(sc, j):
                return Policy(tuple(pts), node(j, visited), node(j, visited))

    return node(sc.start, {sc.start})
