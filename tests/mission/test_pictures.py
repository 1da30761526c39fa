"""Pictures: valid PNGs of a sensible size, drawn headless, with no figure left open."""

from __future__ import annotations

import copy
import io

import matplotlib.image as mpimg
import matplotlib.pyplot as plt
import numpy as np
import pytest
from support.missions import make_plan

from gcs_planner.errors import InputError
from gcs_planner.mission.pictures import (
    error_budget_png,
    front_png,
    route_png,
    sawtooth,
    side_profile,
)


def decode(png: bytes) -> np.ndarray:
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    return mpimg.imread(io.BytesIO(png), format="png")


@pytest.fixture(scope="module")
def route_pictures() -> dict:
    """The tiny plan's routes 0 and 2 drawn once for the module, with the figures open before
    and after: test_route_picture reads route 0, the next test holds it against route 2."""
    plan = make_plan()
    before = plt.get_fignums()
    pictures = {k: route_png(plan, k) for k in (0, 2)}
    return {"before": before, "after": plt.get_fignums(), **pictures}


def test_route_picture(route_pictures):
    # Drawing closes its figures.
    assert route_pictures["after"] == route_pictures["before"]
    img = decode(route_pictures[0])
    h, w = img.shape[:2]
    assert 800 <= w <= 2000 and 600 <= h <= 1400 and w > h
    # Not blank: drawn pixels of several colours (V blue, H orange, A green, B red, the track).
    rgb = img[..., :3].reshape(-1, 3)
    assert (rgb.std(axis=0) > 0.05).all()
    blue = np.sum((rgb[:, 2] > 0.6) & (rgb[:, 0] < 0.3))
    orange = np.sum((rgb[:, 0] > 0.9) & (rgb[:, 1] > 0.4) & (rgb[:, 1] < 0.6) & (rgb[:, 2] < 0.2))
    assert blue > 50 and orange > 50


def test_route_picture_of_another_route_differs(route_pictures):
    assert not np.array_equal(decode(route_pictures[0]), decode(route_pictures[2]))


@pytest.fixture(scope="module")
def front_pictures() -> dict:
    """The tiny plan's front drawn once per case the tests below read, by (probability shown,
    chosen route): the front with probability unshown and route 0 chosen serves both tests."""
    cases = ((True, 0), (False, 0), (False, 1))
    return {(p, c): front_png(make_plan(chosen=c, probability=p)) for p, c in cases}


@pytest.mark.parametrize("probability", [True, False])
def test_front_picture(front_pictures, probability):
    img = decode(front_pictures[probability, 0])
    h, w = img.shape[:2]
    assert 600 <= w <= 1600 and 400 <= h <= 1200


def test_front_picture_marks_the_chosen_route(front_pictures):
    a = decode(front_pictures[False, 0])
    b = decode(front_pictures[False, 1])
    assert a.shape == b.shape and not np.array_equal(a, b)


def test_bad_route_index():
    with pytest.raises(InputError):
        route_png(make_plan(), 7)


# --- the error budget, the side view, the front with one and with fifty routes ---------------


def test_error_budget_picture():
    plan = make_plan()
    before = plt.get_fignums()
    img = decode(error_budget_png(plan))
    assert plt.get_fignums() == before
    h, w = img.shape[:2]
    # Taller when the route is flat: its plan view is then drawn above the error plots.
    assert 1200 <= w <= 2200 and 800 <= h <= 1700 and w > h
    rgb = img[..., :3].reshape(-1, 3)
    red = np.sum((rgb[:, 0] > 0.75) & (rgb[:, 1] < 0.3) & (rgb[:, 2] < 0.3))  # the limits
    assert red > 200
    assert not np.array_equal(img, decode(error_budget_png(plan, 2)))


@pytest.mark.parametrize("component, resets", [("v", "V"), ("h", "H")])
@pytest.mark.parametrize("k", [0, 1, 2])
def test_sawtooth_grows_at_delta_and_drops_at_the_correcting_points(k, component, resets):
    plan = make_plan()
    entry = plan["front"][k]
    delta = plan["parameters"]["delta"]
    x, y = sawtooth(entry, component, resets)
    legs = entry["legs"]
    # x, y: the start of each leg, its end (the arrival), then the start of the next ...
    starts, peaks, afters = y[0::2], y[1::2], y[2::2]
    # The peaks are the arrival errors the plan states, at the distances it states.
    assert peaks == pytest.approx([leg[f"{component}_error"] for leg in legs])
    assert x[1::2] == pytest.approx([leg["cumulative"] for leg in legs])
    # Along each leg the error grows by delta per metre flown.
    runs = x[1::2] - x[0::2][: len(legs)]
    assert peaks - starts[: len(legs)] == pytest.approx(delta * runs, rel=1e-6, abs=1e-9)
    # After a point of the resetting kind the error is 0, after any other it is unchanged.
    for leg, peak, after in zip(legs, peaks, afters, strict=False):
        assert after == (0.0 if leg["kind"] == resets else pytest.approx(peak))


def test_side_view_follows_the_flown_path():
    plan = make_plan()
    for k, entry in enumerate(plan["front"]):
        along, z = side_profile(plan, k)
        assert np.all(np.diff(along) >= 0)
        # Arcs sampled as chords are a hair shorter than flown; never longer.
        assert along[-1] == pytest.approx(entry["length"], rel=1e-5)
        assert along[-1] <= entry["length"] + 1e-6
        first, last = entry["legs"][0]["geometry"]["start"], entry["legs"][-1]["geometry"]["end"]
        assert z[0] == pytest.approx(first[2]) and z[-1] == pytest.approx(last[2])


def many_routes(plan: dict, n: int, seed: int = 0) -> dict:
    """The plan with ``n`` front entries of varied length, corrections and probability."""
    rng = np.random.default_rng(seed)
    front = []
    for _ in range(n):
        entry = copy.deepcopy(plan["front"][0])
        entry["corrections"] = int(rng.integers(3, 20))
        entry["length"] = float(rng.uniform(50_000, 60_000))
        entry["probability"] = float(0.8 ** rng.integers(0, 6))
        front.append(entry)
    return {**plan, "front": front, "chosen": n // 2, "min_probability": 0.99}


@pytest.mark.parametrize("n", [1, 50])
def test_front_picture_reads_with_one_and_with_fifty_routes(n):
    plan = many_routes(make_plan(), n)
    img = decode(front_png(plan))
    h, w = img.shape[:2]
    assert 600 <= w <= 1600 and 400 <= h <= 1200
    if n > 1:  # the chosen ring moves with the choice (one route has no other to choose)
        other = decode(front_png({**plan, "chosen": n - 1}))
        assert not np.array_equal(img, other)
