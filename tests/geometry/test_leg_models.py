"""What every leg model promises the search (issue 28: "the leg model answers for itself"), checked
the same way for each, as OMPL sanity-checks its state spaces: one parametrised test per promise
over every model the planner can build, on seeded random legs.

The promises (gcs_planner/geometry/legs.py):
* ``lower_bounds`` never exceeds the flown length, from any heading (every admissible bound of the
  search is made of it);
* the relaxation's legs are never longer than the model's, and never infeasible where the model's
  are feasible (the heading-free floors and cost-to-go plan on the relaxation);
* ``leg()`` flies the length ``lengths()`` reports and arrives with its heading (tables, exports
  and the dry run fly ``leg()``, the search counts ``lengths()``);
* a model that does not carry a heading gives the same lengths from every heading, and its lower
  bound is the flown length itself (partial routes at one point are then comparable whatever
  their past: the label search's dominance rests on it);
* the compiled lengths equal numpy's (within a few ulp) where a model has them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gcs_planner.geometry.legs import (
    AirplaneLegs,
    CS3DLegs,
    LegModel,
    StraightLegs,
    leg_model_of,
)

# Every model leg_model_of can return, with the radii and climb limits the workbooks and the
# tests use (R = 0 with climb limits: straight legs within the limits, the case that once
# escaped the climb check; cs3d without limits by definition).
MODELS: dict[str, LegModel] = {
    "straight": leg_model_of(0.0),
    "straight-limited": leg_model_of(0.0, max_climb_angle=10.0, max_descent_angle=12.0),
    "cs3d-200": leg_model_of(200.0, "cs3d"),
    "cs3d-1000": leg_model_of(1000.0, "cs3d"),
    "airplane-200": leg_model_of(200.0),
    "airplane-200-limited": leg_model_of(200.0, max_climb_angle=15.0, max_descent_angle=15.0),
    "airplane-1000-limited": leg_model_of(1000.0, max_climb_angle=10.0, max_descent_angle=20.0),
}
REL = 1e-9  # relative slack for float reassociation between two formulas of one length


def _legs(seed: int, m: int = 200) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A start, a horizontal unit heading and ``m`` targets from 0 to 12 km away, some near
    (inside the turning circle), some steep (beyond the climb limits, so helices and
    infeasible legs occur)."""
    rng = np.random.default_rng(seed)
    start = rng.uniform(-1e3, 1e3, 3)
    a = rng.uniform(0, 2 * math.pi)
    heading = np.array([math.cos(a), math.sin(a), 0.0])
    dist = np.concatenate([rng.uniform(0, 2500, m // 2), rng.uniform(2500, 12000, m - m // 2)])
    b = rng.uniform(0, 2 * math.pi, m)
    dz = rng.normal(0, 1, m) * dist * rng.choice([0.05, 0.3, 1.5], m)
    ends = start + np.column_stack([dist * np.cos(b), dist * np.sin(b), dz])
    return start, heading, ends


def test_every_model_kind_is_covered() -> None:
    # A new model class must be added to MODELS (and so to every promise below).
    kinds = {type(m) for m in MODELS.values()}
    assert kinds == {StraightLegs, CS3DLegs, AirplaneLegs}


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("seed", range(5))
def test_lower_bound_never_exceeds_the_flown_length(name: str, seed: int) -> None:
    model = MODELS[name]
    start, heading, ends = _legs(seed)
    bound = model.lower_bounds(start, ends)
    for h in (heading, -heading, None):
        length, _ = model.lengths(start, h, ends)
        finite = np.isfinite(length)
        assert np.all(bound[finite] <= length[finite] * (1 + REL) + 1e-9), name
        # A leg the bound calls infeasible is infeasible from every heading.
        assert not np.any(np.isinf(bound) & finite), name


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("seed", range(5))
def test_relaxation_is_never_longer_and_never_less_feasible(name: str, seed: int) -> None:
    model = MODELS[name]
    relaxed = model.relaxation()
    assert not relaxed.carries_heading  # the floors plan on it heading-free
    assert relaxed.relaxation() is relaxed or relaxed.relaxation() == relaxed
    start, heading, ends = _legs(seed)
    length, _ = model.lengths(start, heading, ends)
    floor, _ = relaxed.lengths(start, None, ends)
    finite = np.isfinite(length)
    assert np.all(np.isfinite(floor[finite])), name
    assert np.all(floor[finite] <= length[finite] * (1 + REL) + 1e-9), name


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("seed", range(3))
def test_leg_flies_the_length_lengths_reports(name: str, seed: int) -> None:
    model = MODELS[name]
    start, heading, ends = _legs(seed, m=60)
    for h in (heading, None):
        length, out = model.lengths(start, h, ends)
        for i, end in enumerate(ends):
            leg = model.leg(start, h, end)
            if not np.isfinite(length[i]):
                assert not leg.reachable or not np.isfinite(leg.length), (name, i)
                continue
            assert leg.reachable, (name, i)
            assert leg.length == pytest.approx(length[i], rel=REL, abs=1e-9), (name, i)
            if out is not None:
                # The heading the next leg starts with: the flown leg's exit heading (3D for
                # the tilted-plane model, horizontal for airplane legs).
                got = np.asarray(leg.heading_out, float)
                assert got == pytest.approx(out[i], abs=1e-7), (name, i)


@pytest.mark.parametrize("name", [n for n, m in MODELS.items() if not m.carries_heading])
@pytest.mark.parametrize("seed", range(5))
def test_heading_free_models_ignore_the_heading(name: str, seed: int) -> None:
    model = MODELS[name]
    start, heading, ends = _legs(seed)
    free, out = model.lengths(start, None, ends)
    assert out is None  # nothing to carry to the next leg
    for h in (heading, -heading, np.array([heading[1], -heading[0], 0.0])):
        length, _ = model.lengths(start, h, ends)
        np.testing.assert_array_equal(length, free)
    # exact bounds: the lower bound is the flown length
    np.testing.assert_allclose(model.lower_bounds(start, ends), free, rtol=REL, atol=1e-9)


@pytest.mark.parametrize("name", [n for n, m in MODELS.items() if m.carries_heading])
@pytest.mark.parametrize("seed", range(3))
def test_heading_carrying_models_depend_on_it(name: str, seed: int) -> None:
    # The converse: a model that says it carries a heading does give other lengths from another
    # heading (else the search would keep apart partial routes it could compare).
    model = MODELS[name]
    start, heading, ends = _legs(seed)
    a, _ = model.lengths(start, heading, ends)
    b, _ = model.lengths(start, -heading, ends)
    both = np.isfinite(a) & np.isfinite(b)
    assert np.any(np.abs(a[both] - b[both]) > 1.0), name


@pytest.mark.parametrize("name", [n for n, m in MODELS.items() if hasattr(m, "compiled_lengths")])
@pytest.mark.parametrize("seed", range(3))
def test_compiled_lengths_equal_numpys(name: str, seed: int) -> None:
    model = MODELS[name]
    start, heading, ends = _legs(seed)
    want, want_heading = model.lengths(start, heading, ends)
    got, got_heading = model.compiled_lengths(start, heading, ends)
    got = np.asarray(got)
    np.testing.assert_array_equal(np.isfinite(got), np.isfinite(want))
    finite = np.isfinite(want)
    np.testing.assert_allclose(got[finite], want[finite], rtol=1e-12, atol=1e-9)
    if want_heading is not None:
        np.testing.assert_allclose(
            np.asarray(got_heading)[finite], want_heading[finite], rtol=0, atol=1e-9
        )


@pytest.mark.parametrize("name", MODELS)
def test_the_model_says_what_its_bounds_are(name: str) -> None:
    """``chord_bounds`` is true exactly when the lower bounds are the chords; ``turns_in_bounds``
    only where legs turn; the relaxation answers for itself the same way."""
    model = MODELS[name]
    start, _, ends = _legs(11)
    chords = np.linalg.norm(ends - start, axis=1)
    for m in (model, model.relaxation()):
        same = np.allclose(m.lower_bounds(start, ends), chords, rtol=REL, atol=0.0)
        assert m.chord_bounds == same, (name, m.name)
        assert not m.turns_in_bounds or (m.carries_heading and m.radius > 0)


@pytest.mark.parametrize("name", MODELS)
def test_the_kernel_legs_fly_what_the_model_flies(name: str) -> None:
    """The numbers the compiled search flies a model with give the model's own lengths."""
    model = MODELS[name]
    kernel = model.kernel_legs()
    if not model.carries_heading:
        # heading-free legs come from the reach graph; a climb-limited R = 0 model still states
        # its limits, which the compiled search's first leg uses
        assert kernel is None or kernel.radius == 0.0
        return
    assert kernel is not None and kernel.radius == model.radius
    from gcs_planner.geometry.airplane_kernel import airplane_lengths
    from gcs_planner.geometry.dubins_kernel import cs_lengths

    start, heading, ends = _legs(12)
    want, _ = model.lengths(start, heading, ends)
    if kernel.kind == "airplane":
        got, _ = airplane_lengths(
            start, heading, ends, kernel.radius, kernel.tan_climb, kernel.tan_descent
        )
    else:
        assert kernel.kind == "cs3d" and math.isinf(kernel.tan_climb)
        got, _ = cs_lengths(start, heading, ends, kernel.radius)
    finite = np.isfinite(want)
    assert np.array_equal(finite, np.isfinite(got))
    assert np.allclose(got[finite], want[finite], rtol=1e-9, atol=1e-6)
