"""The point mass with a roll lag (sim/aircraft.py RollLagPointMass, issue 31's cross-check)."""

from __future__ import annotations

import math

import pytest

from gcs_planner.vehicle import G
from sim.aircraft import (
    ROLL_RATE_DEG_S,
    AircraftState,
    Envelope,
    RollLagPointMass,
    step,
)

ENV = Envelope(45.0, 45.0, 5.0, 5.0)


def test_bank_follows_the_one_asked_with_a_lag_and_turns_less_at_first():
    lag = RollLagPointMass()
    s0 = AircraftState(0.0, 0.0, 700.0, 0.0)
    s = lag.step(s0, ENV, G, 0.0, 0.5)  # asks 45 deg left
    assert -ROLL_RATE_DEG_S * 0.5 <= s.bank_deg < -5.0 and s.bank_deg > -45.0
    instant = step(s0, ENV, G, 0.0, 0.5)
    assert instant.bank_deg == pytest.approx(-45.0)
    assert 0.0 < s.heading < instant.heading  # turned left, but less than the point mass
    for _ in range(10):
        s = lag.step(s, ENV, G, 0.0, 0.5)
    assert s.bank_deg == pytest.approx(-45.0, abs=0.1)
    # Settled, it turns at the point mass's rate: g tan(bank) / TAS.
    s2 = lag.step(s, ENV, G, 0.0, 1.0)
    assert s2.heading - s.heading == pytest.approx(G / 45.0, rel=1e-3)


def test_a_step_flown_again_from_its_start_is_the_same():
    """``exact``: the bank is in the state, so a step cut at a finish line is the same arc."""
    lag = RollLagPointMass()
    s0 = AircraftState(0.0, 0.0, 700.0, 0.3, bank_deg=-10.0)
    a = lag.step(s0, ENV, -G, 1.0, 0.5)
    b = lag.step(s0, ENV, -G, 1.0, 0.5)
    assert (a.x, a.y, a.z, a.heading, a.bank_deg) == (b.x, b.y, b.z, b.heading, b.bank_deg)
    assert a.bank_deg > -10.0  # rolling right towards +45
    assert math.isclose(a.z, 700.5)
