"""The International Standard Atmosphere (ICAO Doc 7488), for the one thing a flight needs of it:
how much faster than its equivalent airspeed (EAS) the aircraft flies through the air (TAS).

Both autopilots hold an airspeed that is equivalent (ArduPlane AIRSPEED_CRUISE, PX4
FW_AIRSPD_TRIM are EAS), and both scale by EAS2TAS = sqrt(rho0 / rho(h)) where a true speed
matters (ArduPilot AP_AHRS::get_EAS2TAS, used by AP_L1_Control::loiter_radius and turn_distance;
PX4 FixedwingPositionControl's _eas2tas and the airspeed module's
calc_true_from_equivalent_airspeed). The workbooks fly at 1 to 7 km, where 25 m/s EAS is 26 to
36 m/s true: turns at a given bank are wider by EAS2TAS squared.

Troposphere: T = T0 - L h, rho / rho0 = (T / T0) ** (g / (R L) - 1), valid to 11 km; above it
the tropopause's temperature holds (isothermal layer) and the density falls exponentially.
R is ICAO's specific gas constant of dry air, 287.05287 J/(kg K).

One atmosphere for the planner and the mock vehicle: what the planner plans with is what the
mock flies. Below sea level it is taken at sea level.

This module imports nothing of the planner, the link or the simulator, so every room can import
it.
"""

from __future__ import annotations

import math

import numpy as np

T0_K = 288.15  # sea-level temperature
LAPSE_K_PER_M = 0.0065
R_AIR = 287.05287  # J / (kg K)
G0 = 9.80665  # standard gravity, m/s^2
TROPOPAUSE_M = 11_000.0
DENSITY_EXPONENT = G0 / (R_AIR * LAPSE_K_PER_M) - 1.0  # 4.2559
T11_K = T0_K - LAPSE_K_PER_M * TROPOPAUSE_M
SIGMA11 = (T11_K / T0_K) ** DENSITY_EXPONENT


def density_ratio(altitude_m: float) -> float:
    """rho(h) / rho0 at ``altitude_m`` above mean sea level (clamped below sea level to 0 m)."""
    h = max(float(altitude_m), 0.0)
    if h <= TROPOPAUSE_M:
        return (1.0 - LAPSE_K_PER_M * h / T0_K) ** DENSITY_EXPONENT
    return SIGMA11 * math.exp(-G0 * (h - TROPOPAUSE_M) / (R_AIR * T11_K))


def eas2tas(altitude_m: float) -> float:
    """True airspeed per unit of equivalent airspeed at ``altitude_m`` (1 at sea level)."""
    return 1.0 / math.sqrt(density_ratio(altitude_m))


def density_ratios(altitude_m: np.ndarray) -> np.ndarray:
    """:func:`density_ratio` at each of the altitudes ``altitude_m`` (metres AMSL)."""
    h = np.maximum(np.asarray(altitude_m, dtype=float), 0.0)
    low = (1.0 - LAPSE_K_PER_M * np.minimum(h, TROPOPAUSE_M) / T0_K) ** DENSITY_EXPONENT
    high = SIGMA11 * np.exp(-G0 * (h - TROPOPAUSE_M) / (R_AIR * T11_K))
    return np.where(h <= TROPOPAUSE_M, low, high)
