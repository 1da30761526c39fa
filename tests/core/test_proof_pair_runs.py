"""The bounds over arrival headings (core/pair_bounds.py) with runs ("Straight at every
landmark", docs/model.md): every leg i -> j flies s_out straight on, turns, and arrives on a
tangent of at least s_in, so it reaches j within asin((2R + s_out) / h) of its chord, and the
next leg j -> t is at least lb(i, j, t).

Held against the legs flown: from a fine fan of headings at i, each leg i -> j is flown (the
compiled legs and numpy's), its arrival heading at j measured against the cone, and the leg
j -> t flown from it; lb(i, j, t) is never above the least of them. And the fronts the search
proves with those bounds equal enumeration of every simple route on random tall scenarios.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.enumeration import THREE, TWO, assert_fronts_close, planned_front
from support.prefix_flight import enumerated_fronts

from gcs_planner.core.pair_bounds import cone_half_angles, pair_leg_bounds
from gcs_planner.geometry.legs import AirplaneLegs, scenario_leg_model
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Parameters

# Headings at i flown per triple: the fan the least next leg is taken over.
FAN = 240


def _triples(seed: int, m: int = 16):
    """Random (i, j, t) over a 6 km box, altitudes spread over 1.5 km (legs that need helices
    under the limits), and a random model with runs."""
    rng = np.random.default_rng(5_100 + seed)
    model = AirplaneLegs(
        float(rng.choice([50.0, 200.0, 500.0])),
        float(rng.uniform(5.0, 30.0)),
        float(rng.uniform(5.0, 30.0)),
        run_in=float(rng.uniform(0.0, 900.0)),
        run_out=float(rng.choice([0.0, rng.uniform(50.0, 900.0)])),
    )
    xyz = rng.uniform(0.0, 6000.0, (3 * m, 3)) * [1.0, 1.0, 0.25]
    i, j, t = np.arange(0, 3 * m, 3), np.arange(1, 3 * m, 3), np.arange(2, 3 * m, 3)
    return rng, model, xyz, i, j, t


def _least_next_legs(model: AirplaneLegs, xyz, i: int, j: int, t: int, compiled: bool):
    """Over a fan of FAN headings at i: the arrival headings at j of the legs i -> j that fly
    (angles to the chord), and the least flown leg j -> t after any of them (inf: none flies)."""
    headings = np.linspace(0.0, 2.0 * math.pi, FAN, endpoint=False)
    fly = model.compiled_lengths if compiled else model.lengths
    angles, least = [], math.inf
    chord = xyz[j, :2] - xyz[i, :2]
    for psi in headings:
        u = np.array([math.cos(psi), math.sin(psi), 0.0])
        length, head = fly(xyz[i], u, xyz[j][None, :])
        if not math.isfinite(length[0]):
            continue
        arrive = head[0]
        cos = (arrive[0] * chord[0] + arrive[1] * chord[1]) / (
            math.hypot(arrive[0], arrive[1]) * math.hypot(*chord)
        )
        angles.append(math.acos(min(1.0, max(-1.0, cos))))
        nxt, _ = fly(xyz[j], arrive, xyz[t][None, :])
        least = min(least, float(nxt[0]))
    return np.array(angles), least


@pytest.mark.parametrize("seed", range(6))
def test_every_leg_arrives_within_its_cone_and_no_next_leg_is_below_the_bound(seed: int) -> None:
    rng, model, xyz, i, j, t = _triples(seed)
    free = model.lower_bounds(np.zeros(3), xyz[t] - xyz[j])  # heading-free, per triple
    lb = pair_leg_bounds(xyz, i, j, t, model, free)
    assert np.all(lb >= free)
    h_ij = np.hypot(*(xyz[j, :2] - xyz[i, :2]).T)
    cones = cone_half_angles(h_ij, model.radius, model.run_out)
    flown = raised = 0
    for x in range(len(i)):
        angles, least = _least_next_legs(model, xyz, i[x], j[x], t[x], compiled=x % 4 != 0)
        assert np.all(angles <= cones[x] + 1e-9), (seed, x)
        if math.isfinite(least):
            flown += 1
            assert lb[x] <= least * (1.0 + 1e-12), (seed, x, lb[x], least)
            raised += lb[x] > free[x] + 1.0
    assert flown >= 10
    if model.run_in + model.run_out + model.radius > 0:
        assert raised >= 1, "the bound must rise above the heading-free one somewhere"


@pytest.mark.parametrize("seed", range(3))
def test_the_next_legs_horizontal_length_changes_no_faster_than_2r_plus_the_run_out(
    seed: int,
) -> None:
    """The sampling's slack rests on |dH/dpsi| <= 2R + s_out for targets beyond 2R + s_out:
    measured on the flown legs (numpy's fan, unlimited climb: H alone) over 1,800 headings."""
    rng = np.random.default_rng(5_300 + seed)
    radius, run_out = float(rng.choice([50.0, 200.0, 500.0])), float(rng.uniform(0.0, 900.0))
    model = AirplaneLegs(radius, 90.0, 90.0, run_out=run_out)
    ends = rng.uniform(-6000.0, 6000.0, (150, 3)) * [1.0, 1.0, 0.0]
    far = np.hypot(ends[:, 0], ends[:, 1]) > (2.0 * radius + run_out) * 1.01
    ends = ends[far]
    psi = np.linspace(0.0, 2.0 * math.pi, 1801)
    H = np.array(
        [model.lengths(np.zeros(3), [math.cos(a), math.sin(a), 0.0], ends)[0] for a in psi]
    )
    assert np.all(np.isfinite(H))
    rate = np.abs(np.diff(H, axis=0)) / np.diff(psi)[:, None]
    assert rate.max() <= (2.0 * radius + run_out) * (1.0 + 1e-6)
    assert rate.max() >= 0.5 * (2.0 * radius + run_out)  # the rate is of that order


def test_the_bound_is_tight_to_within_the_sampling() -> None:
    """On far legs the bound comes within the sampling's slack of the least leg flown: it is not
    a weak bound that passes the test above by being low."""
    close = total = 0
    for seed in range(3):
        rng, model, xyz, i, j, t = _triples(100 + seed)
        free = model.lower_bounds(np.zeros(3), xyz[t] - xyz[j])
        lb = pair_leg_bounds(xyz, i, j, t, model, free)
        for x in range(len(i)):
            _, least = _least_next_legs(model, xyz, i[x], j[x], t[x], compiled=True)
            if math.isfinite(least):
                total += 1
                close += least - lb[x] <= 0.02 * least
    assert close >= 0.7 * total


def _runs_scenario(seed: int):
    """Five correction points, half unreliable, in an 11 km corridor 1.5 km tall, limits of 7
    to 12 km, R 200 or 500 m, climb and descent limits of 8 to 25 degrees: the scenario with
    no runs, and with runs of 100 to 700 m."""
    rng = np.random.default_rng(41_000 + seed)
    params = Parameters(
        *rng.uniform(7_000, 12_000, 5) * 0.001,
        0.001,
        turn_radius=float(rng.choice([200.0, 500.0])),
        p_success=0.8,
        fail_residual=float(rng.uniform(2, 15)),
        max_climb_angle=float(rng.uniform(8, 25)),
        max_descent_angle=float(rng.uniform(8, 25)),
    )
    base = random_scenario(
        5, seed, params=params, box=(11_000, 3_000, 1_500), unreliable_fraction=0.5
    )
    runs = base.with_params(
        approach=float(rng.uniform(100, 700)), departure=float(rng.uniform(100, 700))
    )
    return base, runs


def test_fronts_with_runs_and_three_objectives_equal_enumeration() -> None:
    """The planner's fronts (two and three objectives; three with the bounds over arrival
    headings) equal enumeration of every simple route with runs, and the runs change the
    fronts in the sample (they bite). The fronts without runs are the planner's proven ones
    (held against enumeration without runs by the tests of the search with turns): enumerating
    them again would double the test's work for a count."""
    nonempty = bitten = 0
    for seed in range(12):
        base, scenario = _runs_scenario(seed)
        assert scenario_leg_model(scenario).turns_in_bounds
        # (enumeration.assert_plans_enumeration, every route flown by prefix)
        want = enumerated_fronts(scenario)
        for objectives in (TWO, THREE):
            got = planned_front(scenario, objectives)
            assert_fronts_close(got, want[objectives], f"seed {seed}, {objectives}")
        nonempty += bool(want[THREE])
        bitten += any(_differ(planned_front(base, o), want[o]) for o in (TWO, THREE))
    assert nonempty >= 8
    assert bitten >= 6


def _differ(a: list[tuple], b: list[tuple]) -> bool:
    """Two fronts differ: other corrections or probabilities, or a length off by over 1e-6."""
    return [x[1:] for x in a] != [y[1:] for y in b] or any(
        abs(x[0] - y[0]) > 1e-6 * max(1.0, abs(y[0])) for x, y in zip(a, b)
    )
