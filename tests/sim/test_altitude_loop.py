"""Each autopilot's altitude loop in the mock (sim/navigators/, gcs_planner/aircraft/autopilot.py
``altitude_loop``): TECS flies a height error out over its time constant (ArduPlane
TECS_TIME_CONST, PX4 FW_T_ALT_TC), its pitch limit of auto flight (TECS_PITCH_MAX capped by
PTCH_LIM_MAX_DEG, FW_P_LIM_MAX) bounds the climb, the mock serves both, and the vehicle setup
writes the pitch limit a plan's climbs need."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from gcs_planner.sim.atmosphere import eas2tas
from gcs_planner.sim.guidance import AutopilotParams, fly
from gcs_planner.sim.param_server import parameter_table
from gcs_planner.sim.turbulence import Turbulence, scale_length_w
from gcs_planner.sim.wind import WindModel
from scipy.integrate import quad
from support.flights import FRAME, PROFILE, mission

from gcs_planner.aircraft.autopilot import ARDUPLANE, PX4, autopilot_for
from gcs_planner.mission.vehicle_setup import needs


def test_the_loop_and_the_pitch_limit_are_the_vehicles_parameters():
    """Shipped: 5 s and 15 deg (ArduPlane), 5 s and 30 deg (PX4); set: the vehicle's values,
    ArduPlane's TECS_PITCH_MAX capped by PTCH_LIM_MAX_DEG and replaced by it when 0."""
    assert (AutopilotParams(ARDUPLANE.firmware).altitude_time_constant,
            AutopilotParams(ARDUPLANE.firmware).pitch_limit) == (5.0, 15.0)  # fmt: skip
    assert (AutopilotParams(PX4.firmware).altitude_time_constant,
            AutopilotParams(PX4.firmware).pitch_limit) == (5.0, 30.0)  # fmt: skip
    read = AutopilotParams.from_parameters
    assert read(ARDUPLANE.firmware, {"TECS_TIME_CONST": 8.0}).altitude_time_constant == 8.0
    assert read(ARDUPLANE.firmware, {"TECS_PITCH_MAX": 0.0}).pitch_limit == 20.0
    assert read(ARDUPLANE.firmware, {"TECS_PITCH_MAX": 30.0}).pitch_limit == 20.0
    both = {"TECS_PITCH_MAX": 30.0, "PTCH_LIM_MAX_DEG": 25.0}
    assert read(ARDUPLANE.firmware, both).pitch_limit == 25.0
    assert read(PX4.firmware, {"FW_T_ALT_TC": 3.0, "FW_P_LIM_MAX": 12.0}).pitch_limit == 12.0
    assert read(PX4.firmware, {"FW_T_ALT_TC": 3.0}).altitude_time_constant == 3.0


@pytest.mark.parametrize("flavour", [ARDUPLANE.firmware, PX4.firmware])
def test_the_mock_serves_the_altitude_loop_as_shipped(flavour):
    ap = autopilot_for(flavour)
    table = parameter_table(flavour)
    for name in ap.altitude_loop:
        assert table[name][0] == ap.spec(name).default
    assert ap.refusal(ap.altitude_loop[0], 1.0) is not None  # below the time constant's range


def _height_error_std(time_constant: float, sigma: float, tas: float, length: float) -> float:
    """The loop's height error in Dryden turbulence: e' = -e / T + w, so e is w through
    T / (1 + T s); its variance the integral of |T / (1 + j w T)|^2 Phi_w(w) over w >= 0."""
    tau = length / tas

    def phi(w: float) -> float:
        x = (tau * w) ** 2
        return sigma**2 * tau / math.pi * (1 + 3 * x) / (1 + x) ** 2

    var, _ = quad(lambda w: time_constant**2 / (1 + (w * time_constant) ** 2) * phi(w), 0, np.inf)
    return math.sqrt(var)


@pytest.mark.parametrize("time_constant", [5.0, 10.0])
def test_the_height_error_in_turbulence_is_the_loops(time_constant):
    """A level 150 km leg at 3,000 m on the truth in 1 m/s of vertical turbulence: the height
    error's deviation is the first-order loop's on the Dryden spectrum (within the spread of
    one flight's estimate), and grows with the time constant."""
    z = 3000.0
    items = mission((16, (0, 0, z), {"param2": 1}), (16, (150000, 0, z), {"param2": 1}))
    ap = replace(AutopilotParams(ARDUPLANE.firmware), altitude_time_constant=time_constant)
    wind = WindModel(0.0, 0.0, 0.0, seed=3, turbulence=Turbulence(1.0))
    f = fly(items, FRAME, (0.0, 0.0, z), PROFILE, params=ap, wind=wind)
    settled = f.t > 200.0
    got = float(np.std(f.xyz[settled, 2] - z))
    tas = PROFILE.cruise_airspeed * eas2tas(z)
    want = _height_error_std(time_constant, 1.0, tas, scale_length_w(z))
    assert got == pytest.approx(want, rel=0.25)


def test_the_pitch_limit_bounds_the_climb():
    """Asked to climb 1,000 m over 3 km at TECS_CLMB_MAX 10 m/s, the aircraft climbs at most
    TAS sin(pitch limit)."""
    items = mission((16, (0, 0, 0), {"param2": 1}), (16, (3000, 0, 1000), {"param2": 1}),
                    (16, (9000, 0, 1000), {"param2": 1}))  # fmt: skip
    ap = AutopilotParams(ARDUPLANE.firmware).with_rates(10.0, 10.0)
    for pitch in (10.0, 20.0):
        f = fly(items, FRAME, (0.0, 0.0, 0.0), PROFILE, params=replace(ap, pitch_limit=pitch))
        ceiling = f.tas * math.sin(math.radians(pitch))
        assert np.all(f.climb <= ceiling + 1e-9)
        assert f.climb.max() == pytest.approx(ceiling[np.argmax(f.climb)])


def _plan(climb_rate: float) -> dict:
    """A plan JSON's envelope at 25 m/s EAS climbing at ``climb_rate``, at sea level."""
    envelope = {"cruise_eas": 25.0, "tas": 25.0, "climb_rate": climb_rate, "sink_rate": 5.0,
                "design_wind": 0.0}  # fmt: skip
    return {"vehicle": {"envelope": envelope}, "points": [{"z": 0.0}, {"z": 10.0}]}


def test_the_setup_writes_the_pitch_limit_a_plans_climbs_need():
    """8 m/s at 25 m/s is 18.7 deg: ArduPlane's TECS_PITCH_MAX (15 shipped) is written 19, its
    cap PTCH_LIM_MAX_DEG stays 20; PX4's FW_P_LIM_MAX 30 already suffices. Beyond 45 deg the
    autopilot cannot take it."""
    ap = {n.name: n for n in needs(_plan(8.0), ARDUPLANE.firmware)}
    assert ap["TECS_PITCH_MAX"].least == pytest.approx(math.degrees(math.asin(8 / 25)))
    assert ap["TECS_PITCH_MAX"].set_to == 19.0 and ap["PTCH_LIM_MAX_DEG"].set_to == 20.0
    assert not ap["TECS_PITCH_MAX"].met_by(15.0)
    px4 = {n.name: n for n in needs(_plan(8.0), PX4.firmware)}
    assert px4["FW_P_LIM_MAX"].set_to == 30.0 and px4["FW_P_LIM_MAX"].met_by(30.0)
    steep = {n.name: n for n in needs(_plan(20.0), ARDUPLANE.firmware)}
    assert steep["TECS_PITCH_MAX"].impossible
