"""Properties of the 3D Dubins CS leg, checked against geometry and an independent root-finding
brute force (no expected numbers taken from the implementation)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from gcs_planner.geometry.dubins import CSLeg, cs_leg, cs_lengths

FAST = settings(max_examples=150, deadline=None)

coord = st.floats(-5e4, 5e4, allow_nan=False)
radius = st.one_of(st.just(0.0), st.floats(1e-3, 2000.0), st.sampled_from([200.0, 2000.0]))
positive_radius = st.one_of(st.floats(1.0, 2000.0), st.just(200.0))
distance = st.one_of(st.floats(0.0, 3e4), st.floats(0.0, 5.0), st.just(0.0))


@st.composite
def unit_vectors(draw):
    # Uniform on the sphere by construction: filtering short random vectors out made Hypothesis
    # fail its filter_too_much health check on some seeds.
    z = draw(st.floats(-1.0, 1.0))
    a = draw(st.floats(0.0, 2.0 * math.pi))
    s = math.sqrt(max(0.0, 1.0 - z * z))
    return np.array([s * math.cos(a), s * math.sin(a), z])


@st.composite
def legs(draw, radii=radius):
    """Start, heading, end, R: generic targets plus targets on the heading's axis (ahead, behind)
    and very close to it."""
    p = np.array([draw(coord), draw(coord), draw(st.floats(0.0, 5000.0))])
    u = draw(unit_vectors())
    d = draw(distance)
    kind = draw(st.sampled_from(["generic", "generic", "ahead", "behind", "near_axis"]))
    if kind == "generic":
        q = p + d * draw(unit_vectors())
    elif kind == "ahead":
        q = p + d * u
    elif kind == "behind":
        q = p - d * u
    else:
        side = draw(unit_vectors())
        side = side - (side @ u) * u
        assume(np.linalg.norm(side) > 0.1)
        side /= np.linalg.norm(side)
        sign = draw(st.sampled_from([1.0, -1.0]))
        q = p + sign * d * u + draw(st.floats(1e-9, 1e-3)) * d * side
    return p, u, q, draw(radii)


def _scale(p, q, r) -> float:
    return max(1.0, float(np.abs(p).max()), float(np.abs(q).max()), r)


def _plane_normal(p, u, q) -> np.ndarray:
    """An in-plane normal towards q, built independently of the module (any normal to u when
    q is on the axis: the length does not depend on it then)."""
    w = q - p
    perp = w - (w @ u) * u
    perp = perp - (perp @ u) * u  # again: one pass leaves ulp(|w|) / |perp| of u in it
    if np.linalg.norm(perp) > 1e-13 * max(1.0, np.linalg.norm(w)):
        return perp / np.linalg.norm(perp)
    e = np.eye(3)[int(np.argmin(np.abs(u)))]
    e = e - (e @ u) * u
    return e / np.linalg.norm(e)


def brute_cs_length(p, u, q, r, n=None, grid=20001) -> float:
    """Shortest 'arc then tangent' path by root finding: the first arc angle at which the arc's
    heading points at q (the line from the arc point is tangent to the circle and q is ahead).
    Returns inf when no angle qualifies (q inside the circle)."""
    n = _plane_normal(p, u, q) if n is None else n

    def arc(phi):
        return p + r * math.sin(phi) * u + r * (1.0 - math.cos(phi)) * n

    def g(phi):  # component of (q - arc) towards the centre: zero when the heading points at q
        return float((q - arc(phi)) @ (-math.sin(phi) * u + math.cos(phi) * n))

    def ahead(phi):
        return float((q - arc(phi)) @ (math.cos(phi) * u + math.sin(phi) * n))

    if abs(g(0.0)) <= 1e-12 * max(1.0, float(np.linalg.norm(q - p))) and ahead(0.0) > 0.0:
        return float(np.linalg.norm(q - p))  # already pointing at q
    phis = np.linspace(0.0, 2.0 * math.pi, grid)
    pts = (
        p[None, :]
        + r * np.sin(phis)[:, None] * u[None, :]
        + r * (1.0 - np.cos(phis))[:, None] * n[None, :]
    )
    m = -np.sin(phis)[:, None] * u[None, :] + np.cos(phis)[:, None] * n[None, :]
    gs = np.einsum("ij,ij->i", q[None, :] - pts, m)
    for k in range(grid - 1):
        if gs[k] == 0.0:
            root = phis[k]
        elif gs[k] * gs[k + 1] < 0.0:
            ga, gb = g(phis[k]), g(phis[k + 1])
            if ga * gb < 0.0:
                root = brentq(g, phis[k], phis[k + 1], xtol=1e-15, rtol=1e-15)
            else:  # the grid's rounding and the scalar's disagree on a sign: the root is an end
                root = phis[k] if abs(ga) <= abs(gb) else phis[k + 1]
        else:
            continue
        if ahead(root) > 0.0 or np.linalg.norm(q - arc(root)) < 1e-9:
            return r * root + float(np.linalg.norm(q - arc(root)))
    return math.inf


def _c(p, u, q, r) -> float:
    """Distance from q to the turning centre, computed independently."""
    return float(np.linalg.norm(q - (p + r * _plane_normal(p, u, q))))


@FAST
@given(legs())
def test_leg_geometry(case):
    p, u, q, r = case
    leg = cs_leg(p, u, q, r)
    scale = _scale(p, q, r)
    tol = 1e-9 * scale
    chord = float(np.linalg.norm(q - p))
    if r > 0 and chord > 0:
        # Reachable exactly when q is not inside the circle (margin away from the boundary).
        c = _c(p, u, q, r)
        if abs(c - r) > 1e-6 * scale:
            assert leg.reachable == (c > r)
    if not leg.reachable:
        assert leg.length == math.inf
        return
    assert np.allclose(leg.heading_in, u, atol=1e-15)
    assert leg.length >= chord - tol  # never shorter than the chord
    assert leg.arc_length + leg.straight_length == pytest.approx(leg.length, abs=tol)
    assert np.linalg.norm(leg.heading_out) == pytest.approx(1.0, abs=1e-12)
    if r == 0.0:
        assert leg.length == pytest.approx(chord, abs=tol)
    if leg.centre is None:
        assert leg.arc_angle == 0.0 and leg.sense == 0
        assert np.allclose(leg.tangent_point, p)
        if chord > 1e-9:  # closer points are one point, flown with the heading unchanged
            assert np.allclose(leg.heading_out, (q - p) / chord, atol=1e-9)
        return
    n, centre, tp = leg.normal, leg.centre, leg.tangent_point
    assert abs(n @ u) < 1e-12 and np.linalg.norm(n) == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(centre, p + r * n, atol=tol)  # the arc starts at p, tangent to u
    assert 0.0 <= leg.arc_angle <= 2.0 * math.pi
    assert np.linalg.norm(tp - centre) == pytest.approx(r, abs=tol)  # tangent point on the circle
    radial = (tp - centre) / r
    # (tp - centre) carries the rounding of the coordinates, ~1e-16 scale, divided by r
    assert abs(leg.heading_out @ radial) < 1e-9 + 1e-14 * scale / r  # segment tangent there
    assert abs(leg.heading_out @ np.cross(u, n)) < 1e-9  # and in the plane of the turn
    # the segment leaves the tangent point along heading_out and reaches q
    assert np.allclose(tp + leg.straight_length * leg.heading_out, q, atol=1e-8 * scale)
    # q is in the plane (u, n) through p
    assert abs((q - p) @ np.cross(u, n)) < 1e-8 * scale
    assert leg.sense in (-1, 0, 1)
    z = np.cross(u, n)[2]
    if abs(z) > 1e-9 and leg.arc_angle > 0.0:
        assert leg.sense == (1 if z > 0 else -1)


@FAST
@given(legs(radii=positive_radius))
def test_length_matches_independent_brute_force(case):
    p, u, q, r = case
    c = _c(p, u, q, r)
    assume(abs(c - r) > 1e-3 * r)  # the tangency roots are well separated
    leg = cs_leg(p, u, q, r)
    expected = brute_cs_length(p, u, q, r)
    if expected == math.inf:
        assert not leg.reachable and leg.length == math.inf
    else:
        assert leg.reachable
        assert leg.length == pytest.approx(expected, abs=1e-6)


@FAST
@given(legs())
def test_start_and_continuity_along_the_leg(case):
    p, u, q, r = case
    leg = cs_leg(p, u, q, r)
    assume(leg.reachable and leg.length > 1e-3)
    scale = _scale(p, q, r)
    assert np.allclose(leg.point_at(0.0), p, atol=1e-9 * scale)
    if r > 0:  # with R = 0 the heading jumps to the chord's at once
        assert np.allclose(leg.heading_at(0.0), u, atol=1e-12)
    assert np.allclose(leg.point_at(leg.length), q, atol=1e-8 * scale)
    h = min(1e-3, leg.length / 10)
    # leaves p along u
    if r > 0:
        assert np.allclose((leg.point_at(h) - p) / h, u, atol=h / r + 1e-6 + 1e-9 * scale / h)
    # unit speed, and the heading turns no faster than 1/R, across the tangent point as well
    ss = np.linspace(0.0, leg.length, 401)
    if leg.centre is not None:
        arc = leg.arc_length
        ss = np.sort(np.concatenate([ss, [max(0.0, arc - 1e-7), min(leg.length, arc + 1e-7)]]))
    pts = np.array([leg.point_at(s) for s in ss])
    hds = np.array([leg.heading_at(s) for s in ss])
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert np.all(steps <= np.diff(ss) + 1e-9 * scale)
    turn = np.arccos(np.clip(np.einsum("ij,ij->i", hds[:-1], hds[1:]), -1.0, 1.0))
    if r > 0:
        assert np.all(turn <= np.diff(ss) / r + 1e-6)
    assert np.allclose(leg.heading_at(leg.length), leg.heading_out)


@FAST
@given(legs(), st.floats(0.5, 5000.0))
def test_sample(case, max_step):
    p, u, q, r = case
    leg = cs_leg(p, u, q, r)
    assume(leg.reachable)
    pts = leg.sample(max_step)
    assert np.array_equal(pts[0], p) and np.array_equal(pts[-1], q)
    assume(len(pts) < 200_000)
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    scale = _scale(p, q, r)
    assert np.all(steps <= max_step + 1e-9 * scale)
    assert np.min(np.linalg.norm(pts - leg.tangent_point, axis=1)) <= 1e-9 * scale
    poly = float(steps.sum())
    # chords of the arc are shorter by at most arc * dtheta^2 / 24 with dtheta <= max_step / R
    bound = 0.0 if r == 0 else leg.arc_length * (max_step / r) ** 2 / 24
    assert poly <= leg.length + 1e-8 * scale
    assert leg.length - poly <= bound + 1e-8 * scale


def test_polyline_length_converges():
    leg = cs_leg([0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-300.0, -250.0, 40.0], 200.0)
    steps = (100.0, 50.0, 25.0, 12.5, 1.0)
    errors = [
        leg.length - np.linalg.norm(np.diff(leg.sample(s), axis=0), axis=1).sum() for s in steps
    ]
    assert all(e >= 0 for e in errors)
    assert all(e2 < e1 / 3 for e1, e2 in zip(errors, errors[1:]))
    assert errors[-1] <= leg.arc_length * (1.0 / 200.0) ** 2 / 24 + 1e-9


@FAST
@given(
    st.tuples(coord, coord, coord).map(np.array),
    unit_vectors(),
    st.lists(
        st.tuples(st.floats(-3e4, 3e4), st.floats(-3e4, 3e4), st.floats(-3e3, 3e3)),
        min_size=1,
        max_size=30,
    ),
    radius,
)
def test_vectorised_form_agrees(p, u, offsets, r):
    ends = p[None, :] + np.array(offsets)
    # add on-axis and inside-circle targets to the batch
    ends = np.concatenate([ends, [p + 1000.0 * u, p - 1000.0 * u, p.copy()]], axis=0)
    lengths, headings = cs_lengths(p, u, ends, r)
    assert lengths.shape == (len(ends),) and headings.shape == (len(ends), 3)
    for k, q in enumerate(ends):
        leg = cs_leg(p, u, q, r)
        assert leg.reachable == math.isfinite(lengths[k])
        if leg.reachable:
            assert lengths[k] == pytest.approx(leg.length, abs=1e-9 * max(1.0, leg.length))
            assert np.allclose(headings[k], leg.heading_out, atol=1e-9)
        else:
            assert lengths[k] == math.inf and np.all(np.isnan(headings[k]))


def test_radius_tends_to_zero_gives_the_chord():
    p, u, q = (
        np.array([10.0, -20.0, 5.0]),
        np.array([0.0, 1.0, 0.0]),
        np.array([700.0, -900.0, 80.0]),
    )
    chord = float(np.linalg.norm(q - p))
    leg0 = cs_leg(p, u, q, 0.0)
    assert leg0.length == chord and leg0.centre is None
    assert np.allclose(leg0.heading_out, (q - p) / chord)
    gaps = [cs_leg(p, u, q, r).length - chord for r in (100.0, 10.0, 1.0, 0.1, 1e-3, 1e-6)]
    assert all(g2 < g1 for g1, g2 in zip(gaps, gaps[1:]))
    assert gaps[-1] < 1e-5


@st.composite
def circle_targets(draw):
    """A leg and a target at distance R (1 + delta) from the centre, in the plane of the turn,
    at the arc point of angle phi0."""
    p = np.array([draw(coord), draw(coord), draw(st.floats(0.0, 5000.0))])
    u = draw(unit_vectors())
    side = draw(unit_vectors())
    side = side - (side @ u) * u
    assume(np.linalg.norm(side) > 0.1)
    n = side / np.linalg.norm(side)
    r = draw(st.floats(10.0, 2000.0))
    phi0 = draw(st.floats(0.2, 2.0 * math.pi - 0.2))
    return p, u, n, r, phi0


def _target(p, u, n, r, phi0, delta):
    centre = p + r * n
    on_circle = p + r * math.sin(phi0) * u + r * (1.0 - math.cos(phi0)) * n
    return centre + (1.0 + delta) * (on_circle - centre)


@FAST
@given(circle_targets())
def test_inside_the_turning_circle_is_not_allowed(case):
    p, u, n, r, phi0 = case
    for delta in (-1e-6, -1e-3, -0.5):
        leg = cs_leg(p, u, _target(p, u, n, r, phi0, delta), r)
        assert not leg.reachable and leg.length == math.inf
        lengths, headings = cs_lengths(p, u, _target(p, u, n, r, phi0, delta)[None, :], r)
        assert lengths[0] == math.inf and np.all(np.isnan(headings[0]))
        with pytest.raises(ValueError):
            leg.sample(10.0)


@FAST
@given(circle_targets())
def test_just_outside_the_circle_is_continuous(case):
    p, u, n, r, phi0 = case
    previous = math.inf
    for delta in (1e-2, 1e-4, 1e-6, 1e-8):
        leg = cs_leg(p, u, _target(p, u, n, r, phi0, delta), r)
        assert leg.reachable and math.isfinite(leg.length)
        assert np.allclose(leg.normal, n, atol=1e-6)
        t_bound = 2.0 * r * math.sqrt(2.0 * delta + delta**2)
        assert leg.straight_length <= t_bound + 1e-6
        err = abs(leg.length - r * phi0)  # the limit: the arc up to the target on the circle
        assert err <= 2.0 * t_bound + 1e-6
        assert err <= previous + 1e-6
        previous = err


@settings(max_examples=60, deadline=None)
@given(
    st.tuples(coord, coord, coord).map(np.array),
    unit_vectors(),
    st.floats(1e-3, 3e4),
    st.floats(1.0, 2000.0),
)
def test_target_straight_behind(p, u, d, r):
    q = p - d * u
    leg = cs_leg(p, u, q, r)
    assert leg.reachable
    # length from the geometry of a turn back onto the line: independent of the plane chosen
    expected = r * (2.0 * math.pi - 2.0 * math.atan(d / r)) + d
    assert leg.length == pytest.approx(expected, rel=1e-9, abs=1e-6)
    if d > 0.1 * r:  # else the two tangency roots nearly merge and the grid cannot split them
        any_normal = np.cross(u, [0.3, -0.5, 0.8])
        any_normal /= np.linalg.norm(any_normal)
        assert leg.length == pytest.approx(brute_cs_length(p, u, q, r, any_normal), abs=1e-6)
    assert np.allclose(leg.tangent_point + leg.straight_length * leg.heading_out, q, atol=1e-6)
    # From the origin the target is on the axis to rounding (elsewhere the coordinates' own
    # rounding can put it a few ulp off the axis, which legitimately defines a plane).
    origin = np.zeros(3)
    leg = cs_leg(origin, u, -d * u, r)
    # the documented normal: orthogonal to u, horizontal, on the left (counter-clockwise)
    assert leg.normal is not None
    assert abs(leg.normal @ u) < 1e-12
    if math.hypot(u[0], u[1]) > 1e-6:
        assert leg.normal[2] == 0.0 and leg.sense == 1
        assert np.cross(u, leg.normal)[2] > 0
    again = cs_leg(origin, u, -d * u, r)
    assert np.array_equal(again.normal, leg.normal)


def test_straight_behind_with_vertical_heading_is_deterministic():
    leg = cs_leg([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -500.0], 200.0)
    assert leg.normal is not None and leg.normal[2] == 0.0
    assert leg.sense == 0  # a turn in a vertical plane has no direction seen from above
    assert leg.length == pytest.approx(200.0 * (2 * math.pi - 2 * math.atan(2.5)) + 500.0)


def test_straight_ahead_and_coincident():
    leg = cs_leg([1.0, 2.0, 3.0], [3.0, 4.0, 0.0], [301.0, 402.0, 3.0], 200.0)
    assert leg.centre is None and leg.normal is None and leg.arc_angle == 0.0
    assert leg.length == pytest.approx(500.0) and np.allclose(leg.heading_out, [0.6, 0.8, 0.0])
    same = cs_leg([1.0, 2.0, 3.0], [1.0, 0.0, 0.0], [1.0, 2.0, 3.0], 200.0)
    assert same.reachable and same.length == 0.0
    assert np.array_equal(same.sample(10.0), [[1.0, 2.0, 3.0], [1.0, 2.0, 3.0]])
    # a few ulp away, behind or to the side: still one point, not a full circle
    for end, heading in (
        ([0.0, -5e-324, 0.0], [0.0, 1.0, 0.0]),
        ([-4.85586749347193e-42, 0.0, 0.0], [-1.0, 0.0, 1.17549435e-38]),
        ([0.0, 1e-10, 0.0], [1.0, 0.0, 0.0]),
    ):
        near = cs_leg(np.zeros(3), heading, end, 200.0)
        assert near.reachable and near.centre is None and near.length < 1e-9
        lengths, outs = cs_lengths(np.zeros(3), np.array(heading), np.array([end]), 200.0)
        assert lengths[0] == near.length and np.array_equal(outs[0], near.heading_out)
    # with R = 0 too (the chord's direction would be rounding noise: its square is subnormal)
    tiny = cs_leg(np.zeros(3), [0.0, 1.0, 0.0], [0.0, 0.0, 1.09483012e-158], 0.0)
    assert np.array_equal(tiny.heading_out, [0.0, 1.0, 0.0])


def test_a_tiny_offset_behind_needs_almost_a_full_turn():
    # just behind the start and just outside the circle: the whole circle, then a short tangent
    leg = cs_leg([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-1e-3, 1e-12, 0.0], 200.0)
    assert leg.reachable
    assert 2 * math.pi * 200.0 - 1e-2 < leg.length < 2 * math.pi * 200.0
    assert leg.arc_angle > 2 * math.pi - 1e-4 and leg.straight_length < 1e-2


def test_sense_seen_from_above():
    left = cs_leg([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1000.0, 0.0], 200.0)
    right = cs_leg([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -1000.0, 0.0], 200.0)
    assert left.sense == 1 and right.sense == -1
    assert left.heading_out[1] > 0 and right.heading_out[1] < 0


def test_bad_arguments():
    with pytest.raises(ValueError):
        cs_leg([0, 0, 0], [0, 0, 0], [1, 0, 0], 200.0)
    with pytest.raises(ValueError):
        cs_leg([0, 0, 0], [1, 0, 0], [1, 0, 0], -1.0)
    with pytest.raises(ValueError):
        cs_lengths(np.zeros(3), np.array([1.0, 0, 0]), np.zeros((4, 2)), 200.0)
    leg = cs_leg([0, 0, 0], [1, 0, 0], [0, 1000, 0], 200.0)
    with pytest.raises(ValueError):
        leg.point_at(leg.length + 1.0)
    with pytest.raises(ValueError):
        leg.sample(0.0)
    assert isinstance(leg, CSLeg)
    with pytest.raises(ValueError):
        leg.start[0] = 1.0  # read-only


@settings(max_examples=200, deadline=None)
@given(
    st.tuples(coord, coord, coord).map(np.array),
    unit_vectors(),
    unit_vectors(),
    st.floats(1e-3, 3e4),
    st.floats(-16.0, -4.0),
    st.floats(1.0, 2000.0),
)
def test_nearly_ahead_never_wraps_to_a_full_circle(p, u, side, a, log_ratio, r):
    side = side - (side @ u) * u
    assume(np.linalg.norm(side) > 0.1)
    side /= np.linalg.norm(side)
    b = a * 10.0**log_ratio
    assume(b * b < a * a * 1e-3 and a * a + b * b - 2 * b * r > 1e-6 * a * a)  # outside the circle
    q = p + a * u + b * side
    leg = cs_leg(p, u, q, r)
    chord = float(np.linalg.norm(q - p))
    assert leg.reachable
    assert leg.arc_angle < 0.5 * math.pi
    assert leg.length == pytest.approx(chord, rel=1e-3, abs=1e-6)
    lengths, _ = cs_lengths(p, u, q[None, :], r)
    assert lengths[0] < 1.01 * chord + 1e-6
