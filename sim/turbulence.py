"""Vertical turbulence: the Dryden vertical gust component of the military flying-qualities
standards, its scale length and intensity at altitude, and one seeded step of it.

The spectrum (MIL-F-8785C, "Military Specification: Flying Qualities of Piloted Airplanes",
1980, section 3.7.2.1, the Dryden form; MIL-HDBK-1797, 1997, writes the same spectrum with its
scale length 2 L_w): for the spatial frequency Omega (rad/m),

    Phi_w(Omega) = sigma_w^2 (L_w / pi) (1 + 3 (L_w Omega)^2) / (1 + (L_w Omega)^2)^2,

whose one-sided integral is sigma_w^2. Flown through at the true airspeed V (Taylor's frozen
field) it is the output of (1 + sqrt(3) tau s) / (1 + tau s)^2 with tau = L_w / V driven by
white noise. Written in the distance flown through the air in scale lengths, u = (V / L_w) t,
the filter is (1 + sqrt(3) p) / (1 + p)^2: two states x1' = -x1 + n, x2' = x1 - x2 driven by
unit white noise, stationary covariance [[1/2, 1/4], [1/4, 1/4]], and w = sigma_w (sqrt(3) x1 +
(1 - sqrt(3)) x2) has variance sigma_w^2 exactly. A step of du = dt V / L_w is propagated
exactly (:func:`dryden_step`: the transition e^(-du) [[1, 0], [du, 1]] and the noise's own
covariance over the step, drawn through its Cholesky factor), so the step's length, the
airspeed and the scale length may change from step to step.

Scale length (MIL-F-8785C 3.7.2.1 and 3.7.2.3; JSBSim FGWinds ``ttMilspec`` the same): at low
altitude, h below 1,000 ft, L_w = h (h at least 10 ft); at medium and high altitude, above
2,000 ft, L_w = 1,750 ft; between, linear. Over the sea the height above ground is the
altitude.

Intensity: a number ``sigma_w`` (m/s) is flown at every altitude. The named levels are the
standard's: at low altitude sigma_w = 0.1 W20, W20 the wind at 20 ft, 15 kt light, 30 kt
moderate, 45 kt severe (MIL-F-8785C 3.7.2.3, Fig. 9); at medium and high altitude the curves of
MIL-F-8785C Fig. 7 (sigma against altitude, probability of exceedance 10^-2 light, 10^-3
moderate, 10^-5 severe; the values as JSBSim's FGWinds tabulates them); between 1,000 and
2,000 ft, linear.

Only the vertical component is modelled here: it moves the aircraft off its altitude, which
the autopilot's TECS flies out on its own time constant. The horizontal gusts are sim/wind.py's
(``--gust``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FT = 0.3048  # m
KNOT = 1852.0 / 3600.0  # m/s
SQRT3 = math.sqrt(3.0)

LOW_ALTITUDE_FT = 1000.0
MEDIUM_ALTITUDE_FT = 2000.0
SCALE_LENGTH_HIGH_FT = 1750.0
LOWEST_HEIGHT_FT = 10.0

# MIL-F-8785C Fig. 9 / 3.7.2.3: the wind at 20 ft of each level (knots); sigma_w = 0.1 W20 low.
W20_KNOTS = {"light": 15.0, "moderate": 30.0, "severe": 45.0}
# MIL-F-8785C Fig. 7: sigma (ft/s) at these altitudes (ft), the curves of probability of
# exceedance 10^-2 (light), 10^-3 (moderate) and 10^-5 (severe).
FIG7_ALTITUDE_FT = (500.0, 1750.0, 3750.0, 7500.0, 15000.0, 25000.0, 35000.0, 45000.0, 55000.0,
                    65000.0, 75000.0, 80000.0)  # fmt: skip
FIG7_SIGMA_FPS = {
    "light": (6.6, 6.9, 7.4, 6.7, 4.6, 2.7, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0),
    "moderate": (8.6, 9.6, 10.6, 10.1, 8.0, 6.6, 5.0, 4.2, 2.7, 0.0, 0.0, 0.0),
    "severe": (15.6, 17.6, 23.0, 23.6, 22.1, 20.0, 16.0, 15.1, 12.1, 7.9, 6.2, 5.1),
}
LEVELS = tuple(W20_KNOTS)
# The stationary covariance's Cholesky factor (a flight starts as turbulent as it goes on).
_P11 = math.sqrt(0.5)
_P21 = 0.25 / _P11
_P22 = math.sqrt(0.25 - _P21 * _P21)


def scale_length_w(altitude_m: float) -> float:
    """L_w (m) at ``altitude_m`` (above the sea), MIL-F-8785C (module docstring)."""
    h = max(altitude_m / FT, LOWEST_HEIGHT_FT)
    if h <= LOW_ALTITUDE_FT:
        length = h
    elif h <= MEDIUM_ALTITUDE_FT:
        share = (h - LOW_ALTITUDE_FT) / (MEDIUM_ALTITUDE_FT - LOW_ALTITUDE_FT)
        length = LOW_ALTITUDE_FT + share * (SCALE_LENGTH_HIGH_FT - LOW_ALTITUDE_FT)
    else:
        length = SCALE_LENGTH_HIGH_FT
    return length * FT


@dataclass(frozen=True)
class Turbulence:
    """The vertical turbulence flown: ``sigma_w`` m/s at every altitude, or a named ``level``
    of the standard (its sigma_w depends on the altitude)."""

    sigma_w: float = 0.0
    level: str = ""

    def __post_init__(self) -> None:
        if self.level and self.level not in W20_KNOTS:
            raise ValueError(f"turbulence level must be one of {', '.join(LEVELS)}")
        if not (math.isfinite(self.sigma_w) and self.sigma_w >= 0.0):
            raise ValueError(f"sigma_w must be a speed >= 0 m/s, got {self.sigma_w!r}")

    @property
    def present(self) -> bool:
        return bool(self.level) or self.sigma_w > 0.0

    def table(self) -> tuple[np.ndarray, np.ndarray]:
        """sigma_w (m/s) against altitude (m), piecewise linear, constant beyond its ends."""
        if not self.level:
            return np.array([0.0]), np.array([float(self.sigma_w)])
        low = 0.1 * W20_KNOTS[self.level] * KNOT
        fig7 = np.asarray(FIG7_SIGMA_FPS[self.level]) * FT
        fig7_alt = np.asarray(FIG7_ALTITUDE_FT) * FT
        medium = float(np.interp(MEDIUM_ALTITUDE_FT * FT, fig7_alt, fig7))
        above = fig7_alt > MEDIUM_ALTITUDE_FT * FT
        ends = [0.0, LOW_ALTITUDE_FT * FT, MEDIUM_ALTITUDE_FT * FT]
        alt = np.concatenate([ends, fig7_alt[above]])
        sigma = np.concatenate([[low, low, medium], fig7[above]])
        return alt, sigma

    def sigma_at(self, altitude_m: float) -> float:
        """sigma_w (m/s) at ``altitude_m``."""
        alt, sigma = self.table()
        return float(np.interp(altitude_m, alt, sigma))

    def describe(self) -> str:
        if self.level:
            return (
                f"{self.level} vertical turbulence (Dryden, MIL-F-8785C: sigma_w "
                f"{self.sigma_at(0.0):.2f} m/s low, {self.sigma_at(MEDIUM_ALTITUDE_FT * FT):.2f} "
                "m/s from 2,000 ft)"
            )
        return f"vertical turbulence sigma_w {self.sigma_w:g} m/s (Dryden, MIL-F-8785C)"


def parse_turbulence(text: str) -> Turbulence:
    """``SIGMA_W`` (m/s, 0 to 20) or a level (light, moderate, severe); ValueError otherwise."""
    word = str(text).strip().lower()
    if word in W20_KNOTS:
        return Turbulence(level=word)
    try:
        sigma = float(word)
    except ValueError:
        raise ValueError(
            f"expected SIGMA_W (m/s) or one of {', '.join(LEVELS)}, got {text!r}"
        ) from None
    if not (math.isfinite(sigma) and 0.0 <= sigma <= 20.0):
        raise ValueError(f"sigma_w must lie in [0, 20] m/s, got {text!r}")
    return Turbulence(sigma_w=sigma)


def stationary_state(n1: float, n2: float) -> tuple[float, float]:
    """The filter's state drawn from its stationary distribution by two standard normals."""
    return _P11 * n1, _P21 * n1 + _P22 * n2


def dryden_step(x1: float, x2: float, du: float, n1: float, n2: float) -> tuple[float, float]:
    """The filter's state (x1, x2) after ``du`` scale lengths flown through the air, with two
    standard normals (module docstring; sim/navigator_kernel.py compiles this very function for
    the compiled flight)."""
    if du <= 0.0:
        return x1, x2
    e = math.exp(-du)
    y = 2.0 * du
    e2 = math.exp(-y)
    grown = -math.expm1(-y)
    q11 = 0.5 * grown
    q12 = 0.25 * (grown - y * e2)
    q22 = 0.25 * (grown - e2 * (y + 0.5 * y * y))
    l11 = math.sqrt(q11)
    l21 = q12 / l11
    l22 = math.sqrt(max(q22 - l21 * l21, 0.0))
    return e * x1 + l11 * n1, e * (du * x1 + x2) + l21 * n1 + l22 * n2


def vertical_speed(sigma: float, x1: float, x2: float) -> float:
    """The vertical gust (m/s, up) of the filter's state at intensity ``sigma``."""
    return sigma * (SQRT3 * x1 + (1.0 - SQRT3) * x2)
