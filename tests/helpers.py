"""Shared builders for tests: random scenarios in the shapes that exercise the search."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Kind, Parameters, Scenario


def contest_params(**changes: float) -> Parameters:
    """Dataset 1's limits (alpha 25/15, beta 20/25, theta 30, delta 0.001), corrections that
    succeed with p = 0.8, and ``changes`` (turn radius, failure residual, climb limits)."""
    return Parameters(25, 15, 20, 25, 30, 0.001, **{"p_success": 0.8, **changes})


def corridor_scenario(seed: int, n_min: int = 4, n_max: int = 7) -> Scenario:
    """Sparse scenarios in a narrow corridor with random limits: few chains are feasible, and
    now and then only walks that revisit a point are (the elementarity cases of docs/model.md)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(n_min, n_max + 1))
    a1, a2, b1, b2, th = rng.uniform(5, 20, 5)
    params = Parameters(a1, a2, b1, b2, th, 0.001, turn_radius=0.0)
    length = rng.uniform(15_000, 40_000)
    return random_scenario(n, seed, params=params, box=(length, length * 0.3, length * 0.05))


def mixed_scenario(seed: int, n_min: int = 2, n_max: int = 7) -> Scenario:
    """Random limits and box shapes: dense and sparse, feasible and infeasible."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(n_min, n_max + 1))
    a1, a2, b1, b2 = rng.uniform(5, 30, 4)
    params = Parameters(a1, a2, b1, b2, rng.uniform(5, 30), 0.001, turn_radius=0.0)
    length = rng.uniform(10_000, 60_000)
    box = (length, length * rng.uniform(0.1, 1.0), length * rng.uniform(0.01, 0.3))
    return random_scenario(n, seed, params=params, box=box)


_LETTER = {Kind.A: "A", Kind.B: "B", Kind.V: "V", Kind.H: "H"}


def write_scenario_csv(scenario: Scenario, path: Path) -> Path:
    """The scenario as the CSV the command line reads (id,x,y,z,kind,unreliable; exact floats)."""
    lines = ["id,x,y,z,kind,unreliable"]
    for i in range(scenario.n):
        x, y, z = (float(v) for v in scenario.xyz[i])
        kind = _LETTER[Kind(int(scenario.kind[i]))]
        lines.append(f"{scenario.ids[i]},{x!r},{y!r},{z!r},{kind},{int(scenario.unreliable[i])}")
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def legs_modes(monkeypatch) -> list:  # noqa: ANN001 - pytest's monkeypatch
    """The legs mode (search_kernel.LEGS_*, or None: the Python search) of every search the
    branch and bound runs from now on, appended as they run: so a test can show the compiled
    search really flew its legs."""
    from gcs_planner.core.bnb import search as bnb_search

    modes: list = []
    legs_mode = bnb_search._legs_mode

    def counted(ctx, critical):  # noqa: ANN001, ANN202
        modes.append(legs_mode(ctx, critical))
        return modes[-1]

    monkeypatch.setattr(bnb_search, "_legs_mode", counted)
    return modes
