"""The atmosphere the mock vehicle flies through: the project's one International Standard
Atmosphere (gcs_planner/aircraft/atmosphere.py), read here as the flight reads it
(:func:`eas2tas`, :func:`density_ratio`); the flight kernel (sim/flight_kernel.py) compiles the
same constants."""

from __future__ import annotations

from gcs_planner.aircraft.atmosphere import (
    DENSITY_EXPONENT,
    G0,
    LAPSE_K_PER_M,
    R_AIR,
    SIGMA11,
    T0_K,
    T11_K,
    TROPOPAUSE_M,
    density_ratio,
    eas2tas,
)

# The names the flight kernel has read from here.
_EXPONENT = DENSITY_EXPONENT
_T11 = T11_K
_SIGMA11 = SIGMA11

__all__ = [
    "G0",
    "LAPSE_K_PER_M",
    "R_AIR",
    "T0_K",
    "TROPOPAUSE_M",
    "_EXPONENT",
    "_SIGMA11",
    "_T11",
    "density_ratio",
    "eas2tas",
]
