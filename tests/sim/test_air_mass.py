"""The aircraft in the air mass (sim/aircraft.py, sim/wind.py): it holds its airspeed through
the air, the wind carries it over the ground, its heading differs from its course by the drift
angle, and the gusts are a seeded first-order Gauss-Markov process of the stated deviation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gcs_planner.sim.aircraft import AircraftState, Envelope, step
from gcs_planner.sim.guidance import AutopilotParams, fly
from gcs_planner.sim.wind import WindField, WindModel
from support.flights import FRAME, PROFILE, mission

ENV = Envelope(25.0, 45.0, 5.0, 5.0)


def test_a_steady_wind_carries_the_aircraft_and_turns_its_course_from_its_heading():
    s = AircraftState(0.0, 0.0, 0.0, 0.0)  # heading east
    s1 = step(s, ENV, 0.0, 0.0, 10.0, wind=(0.0, 5.0))  # a southerly: air moving north
    assert (s1.x, s1.y) == pytest.approx((250.0, 50.0))
    assert s1.heading == pytest.approx(0.0)
    assert s1.course == pytest.approx(math.atan2(5.0, 25.0))
    assert s1.ground_speed == pytest.approx(math.hypot(25.0, 5.0))


def test_the_autopilot_holds_the_track_in_a_crosswind_by_crabbing():
    """L1 on the ground velocity: on a long leg across a 10 m/s wind the aircraft stays on the
    track, its heading into the wind by asin(W / V)."""
    items = mission((16, (0, 0, 0), {"param2": 1}), (16, (20000, 0, 0), {"param2": 1}))
    f = fly(items, FRAME, (0.0, 0.0, 0.0), PROFILE, flavour="ardupilot",
            wind=WindModel(10.0, 180.0))  # fmt: skip
    settled = (f.xyz[:, 0] > 5000) & (f.xyz[:, 0] < 19000)
    assert np.abs(f.xyz[settled, 1]).max() < 1.0
    crab = math.asin(10.0 / 25.0)
    assert np.median(f.heading[settled]) == pytest.approx(-crab, abs=0.01)
    assert np.median(f.course[settled]) == pytest.approx(0.0, abs=0.01)


def test_a_tailwind_flattens_the_climb_over_the_ground():
    """The same climb rate over a faster ground speed: a tailwind leaves the aircraft lower at
    the waypoint than a headwind does (why a still-air plan's climbs are lost in wind)."""
    items = mission((16, (0, 0, 0), {"param2": 1}), (16, (3000, 0, 600), {"param2": 1}),
                    (16, (9000, 0, 600), {"param2": 1}))  # fmt: skip
    ap = AutopilotParams("ardupilot")
    z = {}
    for name, frm in (("tail", 270.0), ("head", 90.0)):
        f = fly(items, FRAME, (0.0, 0.0, 0.0), PROFILE, params=ap, wind=WindModel(8.0, frm))
        at = [e for e in f.events if e.kind == "reached" and e.seq == 1][0].sample
        z[name] = f.xyz[at, 2]
    assert z["tail"] < z["head"] - 50.0


def test_gusts_are_seeded_and_of_the_stated_deviation():
    a = WindField(WindModel(0.0, 0.0, 2.0, seed=7), 25.0)
    b = WindField(WindModel(0.0, 0.0, 2.0, seed=7), 25.0)
    xs = np.array([a.step(1.0) for _ in range(20000)])
    assert np.array_equal(xs[:50], np.array([b.step(1.0) for _ in range(50)]))
    assert xs[:, 0].std() == pytest.approx(2.0, rel=0.1)
    lag = np.corrcoef(xs[:-1, 0], xs[1:, 0])[0, 1]
    assert lag == pytest.approx(math.exp(-1.0 / (533.0 / 25.0)), abs=0.02)
