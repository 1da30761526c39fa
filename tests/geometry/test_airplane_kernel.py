"""The compiled airplane and cs3d legs (``geometry.airplane_kernel``, ``dubins_kernel``) against
numpy's (``airplane.airplane_legs``, ``dubins.cs_lengths``), and the branch and bound flying
them from its first label."""

from __future__ import annotations

import numpy as np
from support.enumeration import assert_same_front, front_of, probed_front
from support.scenarios import probed_scenario

from gcs_planner.core import bnb
from gcs_planner.core.bnb import Options, flown
from gcs_planner.geometry.airplane import airplane_legs, slope_tan
from gcs_planner.geometry.airplane_kernel import airplane_lengths
from gcs_planner.geometry.dubins import cs_lengths
from gcs_planner.geometry.dubins_kernel import cs_lengths as compiled_cs_lengths
from gcs_planner.geometry.legs import scenario_leg_model


def test_compiled_airplane_legs_equal_numpys_to_a_few_ulp() -> None:
    """Random legs of every kind: turns either way, targets inside the turning circle
    (unreachable), straight ahead, straight behind, coincident, climbs needing helices."""
    rng = np.random.default_rng(1)
    kinds = {"unreachable": 0, "helix": 0, "ahead": 0, "behind": 0}
    for trial in range(2000):
        radius = float(rng.choice([50.0, 200.0, 1500.0]))
        climb, descent = (float(a) for a in rng.choice([90.0, 20.0, 10.0], 2))
        start = rng.uniform(-5000, 5000, 3)
        heading = rng.normal(size=3)
        ends = start + rng.uniform(-3000, 3000, (12, 3)) * rng.choice([0.1, 1.0])
        if trial % 5 == 0:
            ends[0] = start + np.array([500 * heading[0], 500 * heading[1], 10.0])
            ends[1] = start - np.array([500 * heading[0], 500 * heading[1], -10.0])
            ends[2] = start
        want = airplane_legs(start, heading, ends, radius, climb, descent)
        tangents = slope_tan(climb), slope_tan(descent)
        length, head = airplane_lengths(start, heading, ends, radius, *tangents)
        np.testing.assert_array_equal(np.isinf(length), np.isinf(want.length))
        np.testing.assert_array_equal(np.isnan(head), np.isnan(want.heading))
        ok = np.isfinite(want.length)
        np.testing.assert_allclose(length[ok], want.length[ok], rtol=4e-15, atol=0)
        np.testing.assert_allclose(head[ok], want.heading[ok], rtol=0, atol=1e-14)
        kinds["unreachable"] += int((~ok).sum())
        kinds["helix"] += int((want.helix_turns[ok] > 0).sum())
        kinds["ahead"] += int((want.straight[ok] & (want.length[ok] > 1)).sum())
        kinds["behind"] += int((ok & (want.arc_angle > 3.1415)).sum())
    assert all(count >= 100 for count in kinds.values()), kinds


def test_fronts_flying_compiled_legs_from_the_first_label() -> None:
    """The same fronts as numpy's legs and as enumeration, two and three objectives."""
    compiled, python = Options(compiled_legs_from=-1), Options(compiled_legs=False)
    for legs in ("airplane", "airplane, climb limits", "cs3d"):
        for seed in range(6):
            scenario = probed_scenario(seed, legs)
            for probability in (True, False):
                got = bnb.bnb_front(
                    scenario, probability=probability, max_labels=10**6, options=compiled
                )
                numpy = bnb.bnb_front(
                    scenario, probability=probability, max_labels=10**6, options=python
                )
                assert got.optimal and numpy.optimal
                assert [f.points for f in got.front] == [f.points for f in numpy.front]
                want = probed_front(seed, legs, probability)
                assert_same_front(front_of(got, probability), want, (legs, seed, probability))


def test_compiled_cs3d_legs_equal_numpys_to_a_few_ulp() -> None:
    """The tilted-plane CS legs (``dubins.cs_lengths``): any heading, radius 0 included."""
    rng = np.random.default_rng(3)
    unreachable = straight = 0
    for trial in range(2000):
        radius = float(rng.choice([0.0, 50.0, 200.0, 1500.0]))
        start = rng.uniform(-5000, 5000, 3)
        heading = rng.normal(size=3)
        ends = start + rng.uniform(-3000, 3000, (12, 3)) * rng.choice([0.1, 1.0])
        if trial % 5 == 0:
            u = heading / np.linalg.norm(heading)
            ends[0], ends[1], ends[2] = start + 500 * u, start - 500 * u, start
        want, want_heading = cs_lengths(start, heading, ends, radius)
        got, got_heading = compiled_cs_lengths(start, heading, ends, radius)
        np.testing.assert_array_equal(np.isinf(got), np.isinf(want))
        np.testing.assert_array_equal(np.isnan(got_heading), np.isnan(want_heading))
        ok = np.isfinite(want)
        np.testing.assert_allclose(got[ok], want[ok], rtol=4e-15, atol=0)
        np.testing.assert_allclose(got_heading[ok], want_heading[ok], rtol=0, atol=1e-14)
        unreachable += int((~ok).sum())
        straight += int(np.isclose(want[ok], np.linalg.norm(ends - start, axis=1)[ok]).sum())
    assert unreachable >= 100 and straight >= 100, (unreachable, straight)


def test_seed_routes_flown_compiled_as_flown_route_flies_them() -> None:
    """``bnb.flown._compiled_flight`` (seed routes' legs after the first flown compiled) against
    ``flown_route``: random routes, repeated points (coincident legs) and targets inside the
    turning circle included, with a free heading at A and a given one."""
    import numba  # noqa: F401  (loaded: the compiled flight is what a long search uses)

    rng = np.random.default_rng(11)
    unreachable = 0
    for legs in ("airplane", "airplane, climb limits", "cs3d"):
        for seed in range(8):
            scenario = probed_scenario(seed, legs)
            if seed % 2:
                scenario = scenario.with_vehicle(heading_at_a=tuple(rng.normal(size=3)))
            model = scenario_leg_model(scenario)
            inner = [i for i in range(scenario.n) if i not in (scenario.start, scenario.end)]
            for _ in range(30):
                middle = list(rng.choice(inner, int(rng.integers(1, len(inner))), replace=False))
                if rng.random() < 0.2:
                    middle.insert(int(rng.integers(0, len(middle))), middle[0])
                points = (scenario.start, *map(int, middle), scenario.end)
                got = flown._compiled_flight(scenario, points, model)
                want = [s.leg.length for s in bnb.flown_route(scenario, points).stops[1:]]
                assert got is not None and len(got) == len(want)
                np.testing.assert_array_equal(np.isinf(got), np.isinf(want))
                ok = np.isfinite(want)
                np.testing.assert_allclose(np.array(got)[ok], np.array(want)[ok], rtol=1e-13)
                unreachable += int((~ok).any())
    assert unreachable >= 20, unreachable
