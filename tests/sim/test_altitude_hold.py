"""The altitude-hold error in vertical turbulence (gcs_planner/aircraft/altitude_hold.py): the
closed form is the integral of |H|^2 times the Dryden spectrum, and the mock's flight holds its
altitude within it (Monte Carlo: long straight level legs, several seeded flights pooled)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from gcs_planner.sim.guidance import AutopilotParams, fly
from gcs_planner.sim.turbulence import Turbulence
from gcs_planner.sim.wind import WindModel
from scipy.integrate import quad
from support.flights import FRAME, PROFILE, mission

from gcs_planner.aircraft.altitude_hold import (
    AltitudeHold,
    allowance_factor,
    design_hold,
    height_error_sigma,
)
from gcs_planner.aircraft.autopilot import ARDUPLANE, PX4


@pytest.mark.parametrize("tau", [2.0, 3.0, 5.0, 10.0])
@pytest.mark.parametrize("scale_length", [30.0, 300.0, 533.4])
def test_the_closed_form_is_the_integral_over_the_dryden_spectrum(tau, scale_length):
    tas, sigma = 17.0, 0.8
    big_t = scale_length / tas

    def integrand(w: float) -> float:
        x = (big_t * w) ** 2
        phi = sigma**2 * big_t / math.pi * (1 + 3 * x) / (1 + x) ** 2
        return tau**2 / (1 + (w * tau) ** 2) * phi

    var, _ = quad(integrand, 0, np.inf, limit=200)
    assert height_error_sigma(sigma, tau, tas, scale_length) == pytest.approx(math.sqrt(var))


def test_k_is_the_two_sided_normal_quantile_of_the_miss_probability():
    assert allowance_factor(1e-3) == pytest.approx(3.2905, abs=1e-4)
    assert allowance_factor(0.05) == pytest.approx(1.96, abs=1e-3)
    with pytest.raises(ValueError):
        allowance_factor(0.0)


def test_the_design_takes_the_vehicles_time_constant_else_the_shipped_one():
    t = Turbulence(0.5)
    assert design_hold(None, ARDUPLANE.firmware, 12.0) is None
    assert design_hold(Turbulence(0.0), ARDUPLANE.firmware, 12.0) is None
    shipped = design_hold(t, ARDUPLANE.firmware, 12.0)
    assert (shipped.loop_param, shipped.time_constant) == ("TECS_TIME_CONST", 5.0)
    assert design_hold(t, PX4.firmware, 15.0, {"FW_T_ALT_TC": 2.0}).time_constant == 2.0
    # A tighter loop holds the altitude closer.
    tight = design_hold(t, ARDUPLANE.firmware, 12.0, {"TECS_TIME_CONST": 3.0})
    assert tight.allowance(3000.0) < shipped.allowance(3000.0)


@pytest.mark.parametrize(
    ("flavour", "tau", "altitude", "sigma"),
    [
        (ARDUPLANE.firmware, 5.0, 3000.0, 0.5),
        (ARDUPLANE.firmware, 3.0, 200.0, 1.0),
        (PX4.firmware, 2.0, 3000.0, 0.5),
    ],
)
def test_the_mocks_height_error_in_turbulence_is_the_models(flavour, tau, altitude, sigma):
    """Eight seeded flights of a level 120 km leg on the truth: the pooled deviation of the
    height from the leg's altitude (after the first 200 s) within 7 % of the model's sigma_h
    (the pooled estimate's own spread is about 2 %: some 900 correlation times)."""
    items = mission(
        (16, (0, 0, altitude), {"param2": 1}), (16, (120_000, 0, altitude), {"param2": 1})
    )
    params = AutopilotParams(flavour)
    params = replace(params, altitude_time_constant=tau)
    errors = []
    for seed in range(8):
        wind = WindModel(0.0, 0.0, 0.0, seed=seed, turbulence=Turbulence(sigma))
        f = fly(items, FRAME, (0.0, 0.0, altitude), PROFILE, flavour=flavour, params=params,
                wind=wind)  # fmt: skip
        settled = f.t > 200.0
        errors.append(f.xyz[settled, 2] - altitude)
    got = float(np.sqrt(np.mean(np.concatenate(errors) ** 2)))
    model = AltitudeHold(Turbulence(sigma), tau, PROFILE.cruise_airspeed)
    assert got == pytest.approx(model.sigma_h(altitude), rel=0.07)
