"""Seeded random scenarios in the shapes that exercise the search (dense, sparse, corridors,
climbs, turns, unreliable points), the scenario as the CSV the command line reads, and the
flags that state its parameters."""

from __future__ import annotations

import dataclasses
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


def long_corridor_scenario(seed: int, n: int = 60) -> Scenario:
    """A long narrow corridor: routes of many corrections, several front points."""
    params = Parameters(25, 15, 20, 25, 30, 0.001, turn_radius=0.0, fail_residual=5.0)
    return random_scenario(
        n, seed, params=params, box=(90_000, 6_000, 1_000), unreliable_fraction=0.4
    )


def mixed_scenario(seed: int, n_min: int = 2, n_max: int = 7) -> Scenario:
    """Random limits and box shapes: dense and sparse, feasible and infeasible."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(n_min, n_max + 1))
    a1, a2, b1, b2 = rng.uniform(5, 30, 4)
    params = Parameters(a1, a2, b1, b2, rng.uniform(5, 30), 0.001, turn_radius=0.0)
    length = rng.uniform(10_000, 60_000)
    box = (length, length * rng.uniform(0.1, 1.0), length * rng.uniform(0.01, 0.3))
    return random_scenario(n, seed, params=params, box=box)


def turning_scenario(seed: int, radius: float, max_points: int = 5) -> Scenario:
    """Two to five correction points (at most ``max_points``: the same draws whatever it is),
    half unreliable, turns of ``radius``, dataset 1's limits."""
    rng = np.random.default_rng(seed)
    params = contest_params(turn_radius=radius, fail_residual=float(rng.uniform(2, 15)))
    return random_scenario(
        min(int(rng.integers(2, 6)), max_points),
        seed,
        params=params,
        box=(30_000, 8_000, 1_500),
        unreliable_fraction=0.5,
    )


def uncertain_straight_scenario(seed: int, max_points: int = 5) -> Scenario:
    """Small straight-leg scenarios with many unreliable points, dense or corridor-sparse; 1 to
    5 correction points, at most ``max_points`` (the same draws whatever it is)."""
    rng = np.random.default_rng(10_000 + seed)
    n = min(int(rng.integers(1, 6)), max_points)
    a1, a2, b1, b2 = rng.uniform(6, 30, 4)
    params = Parameters(
        a1,
        a2,
        b1,
        b2,
        rng.uniform(6, 30),
        0.001,
        turn_radius=0.0,
        p_success=float(rng.choice([0.0, 0.5, 0.8, 0.95])),
        fail_residual=float(rng.uniform(1, 12)),
    )
    length = rng.uniform(8_000, 45_000)
    width = rng.uniform(0.1, 1.0) if seed % 2 else 0.3
    return random_scenario(
        n,
        seed,
        params=params,
        box=(length, length * width, length * 0.05),
        unreliable_fraction=float(rng.uniform(0.3, 1.0)),
    )


def climbing_scenario(seed: int, max_points: int = 5) -> Scenario:
    """Turns of several radii (or none) and climb limits, B well above or below A; 2 to 5
    correction points, at most ``max_points`` (the same draws whatever it is)."""
    rng = np.random.default_rng(seed)
    params = contest_params(
        turn_radius=float(rng.choice([0.0, 200.0, 800.0])),
        fail_residual=float(rng.uniform(2, 15)),
        max_climb_angle=float(rng.choice([8.0, 15.0, 25.0])),
        max_descent_angle=float(rng.choice([8.0, 15.0, 30.0])),
    )
    # large altitude differences for the distances, so that helices (or with R = 0,
    # infeasible legs) occur
    scenario = random_scenario(
        min(int(rng.integers(2, 6)), max_points),
        seed,
        params=params,
        box=(16_000, 4_000, 6_000),
        unreliable_fraction=0.5,
    )
    # B well above or below A: the direct leg, and often the whole route, needs a helix
    xyz = scenario.xyz.copy()
    xyz[scenario.end, 2] = xyz[scenario.start, 2] + rng.choice([-1, 1]) * rng.uniform(2_500, 5_000)
    return dataclasses.replace(scenario, xyz=xyz)


def sparse_scenario(seed: int) -> Scenario:
    """A few dozen points in a wide box, turns of several radii or none, unreliable points."""
    rng = np.random.default_rng(seed)
    params = contest_params(
        turn_radius=float(rng.choice([0.0, 200.0, 1500.0])),
        fail_residual=float(rng.uniform(2, 15)),
    )
    n = int(rng.integers(15, 40))
    return random_scenario(
        n, seed, params=params, box=(40_000, 20_000, 1_500), unreliable_fraction=0.3
    )


def tall_scenario(
    seed: int,
    leg_model: str,
    radius: float,
    limited: bool,
    points: tuple[int, int] | None = None,
) -> Scenario:
    """``points`` correction points, the fewer or the more (by default 4 or 5, and 6 for every
    twelfth seed with R = 0: 1,957 routes), half unreliable, in a corridor 30 to 45 km long
    with dataset 1's limits (so that most routes need a V and an H correction), altitudes
    spread over 15 % of its length, A at one end of that range; climb and descent limits of 5
    to 25 degrees when ``limited`` (the same points either way)."""
    rng = np.random.default_rng(seed)
    climb, descent = rng.uniform(5.0, 25.0, 2)
    if not limited:
        climb = descent = 90.0
    params = contest_params(
        turn_radius=radius,
        fail_residual=float(rng.uniform(2, 15)),
        max_climb_angle=float(climb),
        max_descent_angle=float(descent),
    )
    length = float(rng.uniform(30_000, 45_000))
    # Two choices whatever ``points`` are, so that the draws after it are the same.
    six = points is None and radius == 0 and seed % 12 == 5
    fewest = 4 if points is None else points[0]
    n = 6 if six else int(rng.integers(fewest, fewest + 2))
    box = (length, length * rng.uniform(0.05, 0.2), 1.0)
    flat = random_scenario(n, seed, params=params, box=box, unreliable_fraction=0.5)
    xyz = flat.xyz.copy()
    xyz[:, 2] = rng.uniform(0.0, 0.15 * length, len(xyz))
    xyz[0, 2] = 0.0
    if rng.random() < 0.5:  # a descent overall as often as a climb
        xyz[:, 2] = xyz[::-1, 2]
    return dataclasses.replace(flat, xyz=xyz).with_vehicle(leg_model=leg_model)


def probed_scenario(seed: int, legs: str) -> Scenario:
    """Nine to thirteen correction points, half of them unreliable, limits of 10 to 18 km and
    radii of 500 to 1,500 m in a 24 km corridor: routes of several corrections whose turns
    matter, so that the search over simple routes probes many partial routes."""
    rng = np.random.default_rng(70_000 + seed)
    climb = legs == "airplane, climb limits"
    params = Parameters(
        *rng.uniform(10_000, 18_000, 5) * 0.001,
        0.001,
        turn_radius=float(rng.choice([500.0, 1000.0, 1500.0])),
        p_success=float(rng.choice([0.5, 0.8])),
        fail_residual=float(rng.uniform(2, 15)),
        max_climb_angle=float(rng.choice([8.0, 15.0])) if climb else 90.0,
        max_descent_angle=float(rng.choice([8.0, 15.0])) if climb else 90.0,
    )
    scenario = random_scenario(
        int(rng.integers(9, 12)),
        seed,
        params=params,
        box=(24_000, 8_000, 3_000 if climb else 1_000),
        unreliable_fraction=0.5,
    )
    return scenario.with_vehicle(leg_model="cs3d") if legs == "cs3d" else scenario


def contingency_scenario(
    seed: int, radius: float = 0.0, n_max: int = 6, lenient: bool = False
) -> Scenario:
    """Tiny random scenarios with many unreliable points and random limits (mixed_scenario's
    shapes, but with unreliable_fraction 0.5 so that failures matter). ``lenient`` limits make
    random policies arrive more often, so that exact probabilities strictly between 0 and 1 are
    compared, not only 0 and 1."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, n_max + 1))
    low, high = (15, 40) if lenient else (8, 30)
    a1, a2, b1, b2 = rng.uniform(low, high, 4)
    params = Parameters(
        a1, a2, b1, b2, rng.uniform(low, high), 0.001, turn_radius=radius,
        p_success=float(rng.uniform(0.3, 0.9)), fail_residual=float(rng.uniform(1, 10)),
    )  # fmt: skip
    length = rng.uniform(10_000, 40_000)
    box = (length, length * rng.uniform(0.1, 1.0), length * rng.uniform(0.01, 0.3))
    return random_scenario(n, seed, params=params, box=box, unreliable_fraction=0.5)


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


def flags_of(sc: Scenario) -> list[str]:
    """The flags of `gcs-planner plan` that state the scenario's parameters exactly, no reserve
    and no least probability."""
    p = sc.params
    names = ("alpha1", "alpha2", "beta1", "beta2", "theta", "delta", "turn_radius", "p_success",
             "fail_residual", "departure")  # fmt: skip
    out = []
    for name in names:
        out += [f"--{name.replace('_', '-')}", repr(float(getattr(p, name)))]
    return [*out, "--reserve", "0", "--min-probability", "0"]


def windy_envelope(rng: np.random.Generator, altitude: float):  # noqa: ANN201 - DerivedEnvelope
    """An envelope carrying only a design wind of 0.5 to 0.9 of an EAS of 10 to 20 m/s, from a
    drawn direction (nothing of it per leg, so the legs are unchanged): flight time far from a
    multiple of the length (core/flight_time.py)."""
    from gcs_planner.aircraft.profile import DerivedEnvelope

    eas = float(rng.uniform(10.0, 20.0))
    return DerivedEnvelope(
        eas=eas,
        bank_deg=45.0,
        climb_rate=5.0,
        sink_rate=5.0,
        wind=float(rng.uniform(0.5, 0.9)) * eas,
        wind_from=float(rng.uniform(0.0, 360.0)),
        altitude=altitude,
        autopilot=None,
    )
