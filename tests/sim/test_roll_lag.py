"""The point mass rolls into its turns (sim/aircraft.py ``step``, issue 31): its bank follows the
one asked as a first-order lag, and the compiled twin (sim/point_mass_kernel.py ``step``) flies
the same steps. ``arc_step`` is the bank taken at once (the model before the lag)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from gcs_planner.sim import point_mass_kernel as pm
from gcs_planner.sim.aircraft import (
    ROLL_ONE_ARC_DEG_S,
    ROLL_RATE_DEG_S,
    ROLL_SUBSTEP_S,
    ROLL_TAU_S,
    AircraftState,
    Envelope,
    arc_step,
    step,
)
from gcs_planner.sim.flight_records import STATE_SIZE, aircraft_record
from gcs_planner.sim.navigators.airframe import POINT_MASS

from gcs_planner.aircraft.profile import G

ENV = Envelope(45.0, 45.0, 5.0, 5.0)


def test_bank_follows_the_one_asked_with_a_lag_and_turns_less_at_first():
    s0 = AircraftState(0.0, 0.0, 700.0, 0.0)
    s = step(s0, ENV, G, 0.0, 0.5)  # asks 45 deg left
    assert -ROLL_RATE_DEG_S * 0.5 <= s.bank_deg < -5.0 and s.bank_deg > -45.0
    instant = arc_step(s0, ENV, G, 0.0, 0.5)
    assert instant.bank_deg == pytest.approx(-45.0)
    assert 0.0 < s.heading < instant.heading  # turned left, but less than the instant bank
    # The first-order lag: after t the bank is 1 - exp(-t / tau) of the way (no rate limit
    # reached rolling 45 deg in 0.8 s: at most 56 deg/s at the start).
    for _ in range(4):
        s = step(s, ENV, G, 0.0, 0.5)
    t = 2.5
    assert s.bank_deg == pytest.approx(-45.0 * (1.0 - math.exp(-t / ROLL_TAU_S)), abs=0.05)
    for _ in range(20):  # 0.8 ln(45 / 0.001) = 8.6 s to within ROLL_SETTLED_DEG
        s = step(s, ENV, G, 0.0, 0.5)
    assert s.bank_deg == pytest.approx(-45.0, abs=1e-9)  # then taken as the bank asked
    # Settled, it turns at the instant model's rate: g tan(bank) / TAS.
    s2 = step(s, ENV, G, 0.0, 1.0)
    assert s2.heading - s.heading == pytest.approx(G / 45.0, rel=1e-6)


def test_the_roll_rate_is_limited():
    """Reversing a 45 deg bank asks for 90 deg of roll: the first substep would roll 5.5 deg
    in 0.05 s (110 deg/s); the limit holds it to ROLL_RATE_DEG_S."""
    s0 = AircraftState(0.0, 0.0, 700.0, 0.0, bank_deg=45.0)
    s = step(s0, ENV, G, 0.0, ROLL_SUBSTEP_S)
    assert s.bank_deg == pytest.approx(45.0 - ROLL_RATE_DEG_S * ROLL_SUBSTEP_S)
    # A short step (cut at a finish line) too.
    s = step(s0, ENV, G, 0.0, 0.004)
    assert s.bank_deg == pytest.approx(45.0 - ROLL_RATE_DEG_S * 0.004)


def test_a_step_flown_again_from_its_start_is_the_same():
    """``exact``: the bank is in the state, so a step cut at a finish line is the same arc."""
    s0 = AircraftState(0.0, 0.0, 700.0, 0.3, bank_deg=-10.0)
    a = step(s0, ENV, -G, 1.0, 0.5)
    b = step(s0, ENV, -G, 1.0, 0.5)
    assert (a.x, a.y, a.z, a.heading, a.bank_deg) == (b.x, b.y, b.z, b.heading, b.bank_deg)
    assert a.bank_deg > -10.0  # rolling right towards +45
    assert math.isclose(a.z, 700.5)


def test_the_navigators_default_airframe_rolls_into_its_turns():
    assert POINT_MASS.step is step
    s = POINT_MASS.step(AircraftState(0.0, 0.0, 700.0, 0.0), ENV, G, 0.0, 0.5)
    assert -45.0 < s.bank_deg < 0.0


def test_free_turn_turns_on_the_spot_as_before():
    free = Envelope(25.0, 90.0, 5.0, 5.0)
    s0 = AircraftState(0.0, 0.0, 100.0, 0.0)
    a = step(s0, free, 0.0, 0.0, 2.0, heading=1.0)
    assert a.heading == pytest.approx(1.0) and a.bank_deg == 0.0
    assert (a.x, a.y) == pytest.approx((50.0 * math.cos(1.0), 50.0 * math.sin(1.0)))


def test_the_compiled_step_flies_the_python_step():
    """Random states, demands, steps (a finish-line cut, a fine step, a coarse one) and winds
    (rising and sinking air too):
    the kernel's step gives the Python step's state to rounding, bank included; a chain of
    steps carries the bank alike."""
    rng = np.random.default_rng(31)
    env = Envelope(28.0, 35.0, 4.0, 3.0)
    aircraft = aircraft_record(env)
    limit = pm.max_lateral(env.bank_limit_deg)
    out = np.empty(STATE_SIZE)
    settled_seen = 0
    for trial in range(300):
        x, y, z, course, heading = (float(v) for v in rng.uniform(-3, 3, 5) * (150, 150, 150, 1, 1))
        s = AircraftState(x, y, z, course, 10.0, float(rng.uniform(-35, 35)), heading=heading)
        dt = float(rng.choice([0.5, 0.137, 4.0, 0.01]))
        lateral = float(rng.choice([0.0, rng.uniform(-12, 12), 25.0]))
        if trial % 7 == 0:
            lateral = -G * math.tan(math.radians(s.bank_deg))  # already at the bank asked
        elif trial % 7 == 1:  # near it: one arc at the lag's mean turn rate
            near = s.bank_deg + float(rng.uniform(-1, 1)) * ROLL_ONE_ARC_DEG_S / dt
            lateral = -G * math.tan(math.radians(near))
        climb = float(rng.uniform(-6, 6))
        wx, wy = (float(w) for w in rng.uniform(-8, 8, 2))
        wz = float(rng.uniform(-2, 2)) if trial % 2 else 0.0  # rising or sinking air
        e2t = float(rng.uniform(1.0, 1.3))
        state = np.array([s.x, s.y, s.z, s.course, s.t, s.bank_deg, s.climb_rate, s.heading,
                          s.tas, s.ground_speed] + [0.0] * (STATE_SIZE - 10))  # fmt: skip
        for _ in range(3):
            py = step(s, env, lateral, climb, dt, (wx, wy, wz), e2t)
            pm.step(state, aircraft, lateral, climb, dt, wx, wy, wz, e2t, limit, out)
            want = [py.x, py.y, py.z, py.course, py.t, py.bank_deg, py.climb_rate, py.heading,
                    py.tas, py.ground_speed]  # fmt: skip
            assert out[:10] == pytest.approx(want, rel=1e-9, abs=1e-9)
            s, state = py, out.copy()
        settled_seen += abs(-math.degrees(math.atan(lateral / G)) - s.bank_deg) < 1e-6
    assert settled_seen > 20  # the settled case (one arc) was flown too


def test_one_arc_near_the_bank_asked_is_the_substeps(monkeypatch):
    """Within ROLL_ONE_ARC_DEG_S / dt of the bank asked a step is one arc at the lag's mean turn
    rate: the exact lag's bank at its end, the heading and position of fine substeps."""
    import gcs_planner.sim.aircraft as aircraft

    s0 = AircraftState(0.0, 0.0, 700.0, 0.2, bank_deg=-20.0)
    for dt in (0.5, 4.0):
        for share in (1.0, -0.5, 0.02):
            gap = share * ROLL_ONE_ARC_DEG_S / dt
            asked = -20.0 - gap
            lateral = -G * math.tan(math.radians(asked))
            one = step(s0, ENV, lateral, 0.0, dt, (3.0, -2.0))
            assert one.bank_deg == pytest.approx(asked + gap * math.exp(-dt / ROLL_TAU_S))
            with monkeypatch.context() as m:
                m.setattr(aircraft, "ROLL_ONE_ARC_DEG_S", 0.0)
                m.setattr(aircraft, "ROLL_SUBSTEP_S", 0.001)
                fine = aircraft.step(s0, ENV, lateral, 0.0, dt, (3.0, -2.0))
            assert one.bank_deg == pytest.approx(fine.bank_deg, abs=1e-3)
            assert one.heading == pytest.approx(fine.heading, abs=2e-5)
            assert math.hypot(one.x - fine.x, one.y - fine.y) < 0.03
