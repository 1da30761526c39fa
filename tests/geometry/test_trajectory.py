"""Trajectory of a whole route: legs chained by heading, polyline, and the JSON form of a leg."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from gcs_planner.geometry.dubins import cs_leg, cs_lengths
from gcs_planner.geometry.trajectory import (
    Trajectory,
    leg_from_dict,
    leg_to_dict,
    route_trajectory,
)

FAST = settings(max_examples=80, deadline=None)

point = st.tuples(st.floats(-3e4, 3e4), st.floats(-3e4, 3e4), st.floats(0.0, 3000.0)).map(np.array)
radius = st.one_of(st.just(0.0), st.floats(1.0, 2000.0), st.just(200.0))


@st.composite
def headings(draw):
    v = np.array([draw(st.floats(-1.0, 1.0)) for _ in range(3)])
    assume(np.linalg.norm(v) > 0.1)
    return v


@st.composite
def routes(draw):
    xyz = np.array(draw(st.lists(point, min_size=2, max_size=8)))
    assume(np.all(np.linalg.norm(np.diff(xyz, axis=0), axis=1) > 1.0))
    heading = draw(st.one_of(st.none(), headings()))
    return xyz, draw(radius), heading


def _chords(xyz: np.ndarray) -> np.ndarray:
    return np.linalg.norm(np.diff(xyz, axis=0), axis=1)


@FAST
@given(routes())
def test_legs_chain_by_heading(case):
    xyz, r, heading = case
    traj = route_trajectory(xyz, r, heading)
    assert len(traj.legs) == len(xyz) - 1
    for k, leg in enumerate(traj.legs):
        assert np.array_equal(leg.start, xyz[k]) and np.array_equal(leg.end, xyz[k + 1])
    hs = traj.headings()
    assert len(hs) == len(xyz)
    if heading is None:
        assert np.allclose(hs[0], (xyz[1] - xyz[0]) / np.linalg.norm(xyz[1] - xyz[0]))
        assert traj.legs[0].length == pytest.approx(_chords(xyz)[0], rel=1e-12)
    else:
        assert np.allclose(hs[0], heading / np.linalg.norm(heading))
    for k in range(len(traj.legs) - 1):
        if traj.legs[k].reachable:
            # equal up to the renormalisation of the heading the next leg receives
            assert np.allclose(traj.legs[k].heading_out, traj.legs[k + 1].heading_in, atol=1e-15)
            assert np.array_equal(hs[k + 1], traj.legs[k].heading_out)


@FAST
@given(routes())
def test_length_agrees_with_chained_vectorised_legs(case):
    xyz, r, heading = case
    traj = route_trajectory(xyz, r, heading)
    chords = _chords(xyz)
    # chain the vectorised form independently of route_trajectory
    if heading is None:
        total, u, first = chords[0], (xyz[1] - xyz[0]) / chords[0], 1
    else:
        total, u, first = 0.0, heading / np.linalg.norm(heading), 0
    for k in range(first, len(xyz) - 1):
        lengths, outs = cs_lengths(xyz[k], u, xyz[k + 1][None, :], r)
        total += lengths[0]
        if not math.isfinite(total):
            break
        u = outs[0]
    if math.isfinite(total):
        assert traj.reachable
        assert traj.length == pytest.approx(total, rel=1e-9)
        assert traj.length >= chords.sum() * (1 - 1e-12)
        if r == 0.0:
            assert traj.length == pytest.approx(chords.sum(), rel=1e-12)
    else:
        assert not traj.reachable and traj.length == math.inf


@FAST
@given(routes(), st.floats(5.0, 2000.0))
def test_polyline(case, max_step):
    xyz, r, heading = case
    traj = route_trajectory(xyz, r, heading)
    assume(traj.reachable)
    poly = traj.polyline(max_step)
    assert np.array_equal(poly[0], xyz[0]) and np.array_equal(poly[-1], xyz[-1])
    for p in xyz:  # every route point is a vertex
        assert np.min(np.linalg.norm(poly - p, axis=1)) == 0.0
    steps = np.linalg.norm(np.diff(poly, axis=0), axis=1)
    assert np.all(steps <= max_step + 1e-9 * 3e4)
    flown = float(steps.sum())
    arcs = sum(leg.arc_length for leg in traj.legs)
    bound = 0.0 if r == 0 else arcs * (max_step / r) ** 2 / 24
    assert flown <= traj.length * (1 + 1e-12) + 1e-6
    assert traj.length - flown <= bound + 1e-6


@FAST
@given(routes())
def test_heading_is_continuous_along_the_route(case):
    xyz, r, heading = case
    assume(r > 0)
    traj = route_trajectory(xyz, r, heading)
    assume(traj.reachable)
    for k, leg in enumerate(traj.legs):
        ss = np.linspace(0.0, leg.length, 200)
        hs = np.array([leg.heading_at(s) for s in ss])
        turn = np.arccos(np.clip(np.einsum("ij,ij->i", hs[:-1], hs[1:]), -1.0, 1.0))
        assert np.all(turn <= np.diff(ss) / r + 1e-6)  # never sharper than the radius allows
        if k + 1 < len(traj.legs):
            nxt = traj.legs[k + 1]
            assert np.allclose(leg.heading_at(leg.length), nxt.heading_at(0.0), atol=1e-12)
            assert np.allclose(leg.point_at(leg.length), nxt.point_at(0.0), atol=1e-6)


def test_route_through_a_point_inside_a_turning_circle():
    # heading east at A, the next point is 100 m north: inside the 200 m turning circle
    xyz = np.array([[0.0, 0.0, 0.0], [0.0, 100.0, 0.0], [5000.0, 100.0, 0.0]])
    traj = route_trajectory(xyz, 200.0, np.array([1.0, 0.0, 0.0]))
    assert not traj.reachable and traj.length == math.inf
    with pytest.raises(ValueError, match="leg 0"):
        traj.polyline()
    # free heading at A: the first leg is straight and the route is flyable
    free = route_trajectory(xyz, 200.0)
    assert free.reachable and math.isfinite(free.length)


def test_bad_route_shape():
    with pytest.raises(ValueError):
        route_trajectory(np.zeros((1, 3)), 200.0)
    with pytest.raises(ValueError):
        route_trajectory(np.zeros((3, 2)), 200.0)


@FAST
@given(point, headings(), point, radius)
def test_leg_dict_round_trip(p, u, q, r):
    leg = cs_leg(p, u, q, r)
    assume(leg.reachable)
    d = json.loads(json.dumps(leg_to_dict(leg), allow_nan=False))
    assert set(d) == {
        "start",
        "heading_in",
        "end",
        "radius",
        "arc",
        "tangent_point",
        "heading_out",
        "arc_length",
        "straight_length",
        "length",
        "path_angle_deg",
        "model",
        "helix_turns",
    }
    assert d["helix_turns"] == 0 and d["model"] == ("cs3d" if r > 0 else "straight")
    if leg.centre is None:
        assert d["arc"] is None
    else:
        assert set(d["arc"]) == {"centre", "normal", "angle", "sense", "length"}
        assert d["arc"]["sense"] == leg.sense
        assert d["arc"]["length"] == pytest.approx(d["arc_length"])
    assert d["arc_length"] + d["straight_length"] == pytest.approx(d["length"], abs=1e-9)
    back = leg_from_dict(d)
    for name in ("start", "heading_in", "end", "tangent_point", "heading_out"):
        assert np.array_equal(getattr(back, name), getattr(leg, name))
    assert back.radius == leg.radius and back.arc_angle == leg.arc_angle
    assert (back.centre is None) == (leg.centre is None)
    assert back.length == leg.length and back.sense == leg.sense
    assert np.array_equal(back.sample(100.0), leg.sample(100.0))


def test_leg_dict_errors():
    good = leg_to_dict(cs_leg([0, 0, 0], [1, 0, 0], [0, 1000, 0], 200.0))
    for field in ("start", "heading_out", "radius"):
        broken = dict(good)
        del broken[field]
        with pytest.raises(ValueError, match=field):
            leg_from_dict(broken)
    broken = dict(good, end=[1.0, 2.0])
    with pytest.raises(ValueError, match="end"):
        leg_from_dict(broken)
    broken = dict(good, arc=dict(good["arc"], angle="x"))
    with pytest.raises(ValueError, match="angle"):
        leg_from_dict(broken)
    with pytest.raises(ValueError):
        leg_to_dict(cs_leg([0, 0, 0], [1, 0, 0], [0, 100, 0], 200.0))  # inside the circle


def test_trajectory_of_straight_legs():
    xyz = np.array([[0.0, 0.0, 0.0], [3000.0, 4000.0, 0.0], [3000.0, 4000.0, 1200.0]])
    traj = route_trajectory(xyz, 0.0)
    assert isinstance(traj, Trajectory)
    assert traj.length == pytest.approx(6200.0)
    hs = traj.headings()  # arrival headings: the chords' directions when R = 0
    assert np.allclose(hs[0], [0.6, 0.8, 0.0]) and np.allclose(hs[1], [0.6, 0.8, 0.0])
    assert np.allclose(hs[2], [0.0, 0.0, 1.0])
