"""Seeded random scenarios shaped like the contest data, for tests and benchmarks."""

from __future__ import annotations

import numpy as np

from gcs_planner.scenario.model import Kind, Parameters, Scenario

# The paper's Table 2, dataset 1 and dataset 2 (docs/model.md).
DATASET1 = Parameters(alpha1=25, alpha2=15, beta1=20, beta2=25, theta=30, delta=0.001)
DATASET2 = Parameters(alpha1=20, alpha2=10, beta1=15, beta2=20, theta=20, delta=0.001)


def random_scenario(
    n_corrections: int,
    seed: int,
    *,
    params: Parameters = DATASET1,
    box: tuple[float, float, float] = (100_000.0, 100_000.0, 10_000.0),
    unreliable_fraction: float = 0.24,
    name: str | None = None,
) -> Scenario:
    """A scenario like the contest's: A at the middle of the west face, B on the east face,
    ``n_corrections`` points uniform in ``box``, V and H in equal odds.

    A small ``box`` relative to ``params.reach_m`` gives dense scenarios; a large one sparse
    scenarios where few chains are feasible (the cases that test elementarity).
    """
    rng = np.random.default_rng(seed)
    bx, by, bz = box
    a = np.array([0.0, by / 2, bz / 2])
    b = np.array([bx, rng.uniform(0.25, 0.75) * by, rng.uniform(0.25, 0.75) * bz])
    pts = rng.uniform([0, 0, 0], [bx, by, bz], size=(n_corrections, 3))
    kinds = np.where(rng.random(n_corrections) < 0.5, Kind.V, Kind.H).astype(np.uint8)
    unreliable = rng.random(n_corrections) < unreliable_fraction
    xyz = np.vstack([a, pts, b])
    kind = np.concatenate([[Kind.A], kinds, [Kind.B]]).astype(np.uint8)
    flags = np.concatenate([[False], unreliable, [False]])
    ids = tuple(str(i) for i in range(n_corrections + 2))
    return Scenario(
        ids=ids,
        xyz=xyz,
        kind=kind,
        unreliable=flags,
        params=params,
        name=name or f"random-{n_corrections}-{seed}",
        source=f"generated(seed={seed})",
    )
