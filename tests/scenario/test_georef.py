"""The local frame: azimuthal equidistant on WGS84, held against independent geodesics."""

from __future__ import annotations

import math

import numpy as np
import pyproj
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcs_planner.errors import InputError
from gcs_planner.scenario.georef import DEFAULT_ORIGIN, LocalFrame, parse_origin
from gcs_planner.scenario.model import Origin

GEOD = pyproj.Geod(ellps="WGS84")

origins = st.builds(
    Origin,
    lat=st.floats(min_value=-80.0, max_value=80.0),
    lon=st.floats(min_value=-180.0, max_value=180.0),
    alt=st.floats(min_value=-100.0, max_value=3000.0),
)
local = st.floats(min_value=-120_000.0, max_value=120_000.0)


# One draw checks both properties: each holds on all 150 draws, and the frame (two pyproj
# transformers, most of the test's work) is built once per drawn origin, not twice.
@settings(max_examples=150, deadline=None)
@given(origin=origins, x=local, y=local, z=st.floats(min_value=-500.0, max_value=12_000.0))
def test_local_coordinates_are_polar_from_the_origin_and_round_trip_under_a_millimetre(
    origin, x, y, z
):
    frame = LocalFrame(origin)
    lat, lon, alt = frame.to_geodetic(x, y, z)
    # Distance and azimuth from the origin are the local polar coordinates.
    az, _, dist = GEOD.inv(origin.lon, origin.lat, lon, lat)
    r = math.hypot(x, y)
    assert dist == pytest.approx(r, abs=0.05)
    if r > 1.0:
        # The azimuth error as a distance across the line of sight.
        d_az = (az - math.degrees(math.atan2(x, y)) + 180.0) % 360.0 - 180.0
        assert abs(math.radians(d_az)) * r < 0.05
    assert alt == pytest.approx(z + origin.alt, abs=1e-9)
    # Local -> geodetic -> local comes back within a millimetre.
    back = frame.to_local(lat, lon, alt)
    assert math.dist(back, (x, y, z)) < 1e-3


def test_vectorised_matches_scalar_and_points_100_km_away():
    frame = LocalFrame(Origin(30.5, 123.5, 7.0))
    xs = np.array([100_000.0, 0.0, -70_710.7, 0.0])
    ys = np.array([0.0, 100_000.0, -70_710.7, 0.0])
    zs = np.array([5000.0, 10.0, 0.0, -7.0])
    lat, lon, alt = frame.to_geodetic(xs, ys, zs)
    assert lat.shape == (4,)
    for k in range(4):
        one = frame.to_geodetic(xs[k], ys[k], zs[k])
        assert isinstance(one[0], float)
        assert one == pytest.approx((lat[k], lon[k], alt[k]), abs=1e-12)
        az, _, dist = GEOD.inv(123.5, 30.5, lon[k], lat[k])
        assert dist == pytest.approx(math.hypot(xs[k], ys[k]), abs=0.05)
    # A flat-earth formula would be far off at 100 km; this is the ellipsoid's answer.
    lon_east, lat_east, _ = GEOD.fwd(123.5, 30.5, 90.0, 100_000.0)
    assert (lat[0], lon[0]) == pytest.approx((lat_east, lon_east), abs=1e-9)
    assert alt[3] == pytest.approx(0.0)


def test_default_origin_is_at_sea_in_range():
    assert -90 <= DEFAULT_ORIGIN.lat <= 90 and -180 <= DEFAULT_ORIGIN.lon <= 180
    LocalFrame(DEFAULT_ORIGIN)


@pytest.mark.parametrize(
    "origin",
    [
        Origin(90.5, 0.0),
        Origin(-91.0, 0.0),
        Origin(float("nan"), 0.0),
        Origin(0.0, 181.0),
        Origin(0.0, float("inf")),
        Origin(0.0, 0.0, float("nan")),
    ],  # fmt: skip
)
def test_bad_origins_are_input_errors(origin):
    with pytest.raises(InputError, match="origin"):
        LocalFrame(origin)


def test_parse_origin():
    assert parse_origin("30.5,123.25") == Origin(30.5, 123.25, 0.0)
    assert parse_origin(" -12.5 , 45 , 100 ") == Origin(-12.5, 45.0, 100.0)
    for bad in ("30.5", "1,2,3,4", "north,east", "95,10", "nan,0"):
        with pytest.raises(InputError) as err:
            parse_origin(bad)
        assert err.value.field == "--origin"
