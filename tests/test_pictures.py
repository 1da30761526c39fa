"""Pictures: valid PNGs of a sensible size, drawn headless, with no figure left open."""

from __future__ import annotations

import io

import matplotlib.image as mpimg
import matplotlib.pyplot as plt
import numpy as np
import pytest
from test_mission_builder import make_plan

from gcs_planner.errors import InputError
from gcs_planner.mission.pictures import front_png, route_png


def decode(png: bytes) -> np.ndarray:
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    return mpimg.imread(io.BytesIO(png), format="png")


def test_route_picture():
    before = plt.get_fignums()
    img = decode(route_png(make_plan()))
    assert plt.get_fignums() == before
    h, w = img.shape[:2]
    assert 800 <= w <= 2000 and 600 <= h <= 1400 and w > h
    # Not blank: drawn pixels of several colours (V blue, H orange, A green, B red, the track).
    rgb = img[..., :3].reshape(-1, 3)
    assert (rgb.std(axis=0) > 0.05).all()
    blue = np.sum((rgb[:, 2] > 0.6) & (rgb[:, 0] < 0.3))
    orange = np.sum((rgb[:, 0] > 0.9) & (rgb[:, 1] > 0.4) & (rgb[:, 1] < 0.6) & (rgb[:, 2] < 0.2))
    assert blue > 50 and orange > 50


def test_route_picture_of_another_route_differs():
    plan = make_plan()
    assert not np.array_equal(decode(route_png(plan, 0)), decode(route_png(plan, 2)))


@pytest.mark.parametrize("probability", [True, False])
def test_front_picture(probability):
    img = decode(front_png(make_plan(probability=probability)))
    h, w = img.shape[:2]
    assert 600 <= w <= 1600 and 400 <= h <= 1200


def test_front_picture_marks_the_chosen_route():
    a = decode(front_png(make_plan(chosen=0, probability=False)))
    b = decode(front_png(make_plan(chosen=1, probability=False)))
    assert a.shape == b.shape and not np.array_equal(a, b)


def test_bad_route_index():
    with pytest.raises(InputError):
        route_png(make_plan(), 7)
