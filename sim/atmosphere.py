"""The International Standard Atmosphere's troposphere, for the one thing the flight needs of it:
how much faster than its equivalent airspeed (EAS) the aircraft flies through the air (TAS).

Both autopilots hold an airspeed that is equivalent (ArduPlane AIRSPEED_CRUISE, PX4
FW_AIRSPD_TRIM are EAS), and both scale by EAS2TAS = sqrt(rho0 / rho(h)) where a true speed
matters (ArduPlane AP_AHRS::get_EAS2TAS, used by AP_L1_Control::loiter_radius and
turn_distance; PX4 FixedwingPositionControl's _eas2tas). The workbooks fly at 1 to 7 km, where
25 m/s EAS is 26 to 36 m/s true: turns at a given bank are wider by EAS2TAS squared.

ISA troposphere (ICAO Doc 7488): T = T0 - L h, rho / rho0 = (T / T0) ** (g / (R L) - 1), valid
to 11 km; above it the model holds the tropopause's temperature (isothermal layer).
"""

from __future__ import annotations

import math

T0_K = 288.15  # sea-level temperature
LAPSE_K_PER_M = 0.0065
R_AIR = 287.05287  # J / (kg K)
G0 = 9.80665
TROPOPAUSE_M = 11_000.0
_EXPONENT = G0 / (R_AIR * LAPSE_K_PER_M) - 1.0  # 4.2559
_T11 = T0_K - LAPSE_K_PER_M * TROPOPAUSE_M
_SIGMA11 = (_T11 / T0_K) ** _EXPONENT


def density_ratio(altitude_m: float) -> float:
    """rho(h) / rho0 at ``altitude_m`` above mean sea level (clamped below sea level to 0 m)."""
    h = max(float(altitude_m), 0.0)
    if h <= TROPOPAUSE_M:
        return (1.0 - LAPSE_K_PER_M * h / T0_K) ** _EXPONENT
    return _SIGMA11 * math.exp(-G0 * (h - TROPOPAUSE_M) / (R_AIR * _T11))


def eas2tas(altitude_m: float) -> float:
    """True airspeed per unit of equivalent airspeed at ``altitude_m`` (1 at sea level)."""
    return 1.0 / math.sqrt(density_ratio(altitude_m))
