"""The autopilot's altitude-hold error in vertical turbulence, and the vertical allowance a
capture is given for it (docs/model.md, "Turbulence in the plan").

The loop: both autopilots fly a height error out on one time constant tau, ArduPlane's
TECS_TIME_CONST (AP_TECS.cpp, ``AP_TECS::_update_pitch``: the height rate demand is the height
error over the time constant) and PX4's FW_T_ALT_TC (TECS.cpp,
``TECS::_calcAltitudeControlOutput``), and the air carries the aircraft up and down with it, so
the height error e obeys e' = -e / tau + w with w the vertical gust: e is w through
tau / (1 + tau s). The gust is Dryden's vertical component (sim/turbulence.py, MIL-F-8785C
3.7.2.1) flown through at the true airspeed V, of correlation time T = L_w / V. With r = tau / T
the integral of |H|^2 times the Dryden spectrum has the closed form

    sigma_h^2 = sigma_w^2 tau^2 (r + 2) / (2 (r + 1)^2),

(partial fractions in (T omega)^2: the integrand (1 + 3x^2) / ((1 + x^2)^2 (1 + r^2 x^2))
integrates to (pi / 2)(r + 2) / (r + 1)^2 over x >= 0). As r -> 0 (the gust steady over the
loop) it is sigma_w tau: the loop holds a climb of w with an error of w tau.

The allowance: e is a zero-mean normal (a linear filter of Gaussian noise), so |e| exceeds
k sigma_h with probability 2 (1 - Phi(k)); k is chosen for a stated miss probability per
capture (1e-3: k = 3.29). The climb and sink rates clip the loop's demand only at gusts of
several m/s, far beyond the sigma_w this is used for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from statistics import NormalDist

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.aircraft.profile import tas_from_eas
from gcs_planner.sim.turbulence import Turbulence, scale_length_w

# The probability that one capture's height error exceeds its allowance (two-sided normal).
CAPTURE_MISS_PROBABILITY = 1e-3


def allowance_factor(miss_probability: float = CAPTURE_MISS_PROBABILITY) -> float:
    """k such that P(|e| > k sigma_h) = ``miss_probability`` for a zero-mean normal e."""
    if not 0.0 < miss_probability < 1.0:
        raise ValueError(f"a miss probability lies in (0, 1), got {miss_probability!r}")
    return NormalDist().inv_cdf(1.0 - miss_probability / 2.0)


def height_error_sigma(
    sigma_w: float, time_constant: float, tas: float, scale_length: float
) -> float:
    """sigma_h (m): the standard deviation of the height error of a loop of ``time_constant``
    seconds flying at ``tas`` m/s through Dryden vertical gusts of ``sigma_w`` m/s and scale
    length ``scale_length`` m (module docstring)."""
    if sigma_w <= 0.0:
        return 0.0
    r = time_constant * tas / scale_length
    return sigma_w * time_constant * math.sqrt((r + 2.0) / (2.0 * (r + 1.0) ** 2))


@dataclass(frozen=True)
class AltitudeHold:
    """A design turbulence met by an autopilot's altitude loop of ``time_constant`` s (the
    parameter ``loop_param``), the aircraft at ``cruise_eas`` m/s EAS: the height error's
    deviation and the vertical allowance at any altitude."""

    turbulence: Turbulence
    time_constant: float
    cruise_eas: float
    loop_param: str = ""
    miss_probability: float = CAPTURE_MISS_PROBABILITY

    @property
    def k(self) -> float:
        return allowance_factor(self.miss_probability)

    def sigma_h(self, altitude_m: float) -> float:
        """sigma_h (m) at ``altitude_m`` above the sea: the TAS, scale length and (for a named
        level) sigma_w of that altitude."""
        return height_error_sigma(
            self.turbulence.sigma_at(altitude_m),
            self.time_constant,
            tas_from_eas(self.cruise_eas, altitude_m),
            scale_length_w(altitude_m),
        )

    def allowance(self, altitude_m: float) -> float:
        """The vertical allowance k sigma_h (m) of a capture at ``altitude_m``."""
        return self.k * self.sigma_h(altitude_m)

    def describe(self) -> str:
        loop = f"{self.loop_param} " if self.loop_param else ""
        return (
            f"{self.turbulence.describe()} through the altitude loop ({loop}{self.time_constant:g}"
            f" s): vertical allowance {self.k:.2f} sigma_h at each capture (miss probability "
            f"{self.miss_probability:g} per capture)"
        )

    def to_dict(self) -> dict[str, object]:
        t = self.turbulence
        return {
            "sigma_w_m_s": None if t.level else t.sigma_w,
            "level": t.level or None,
            "time_constant_s": self.time_constant,
            "loop_param": self.loop_param or None,
            "cruise_eas_m_s": self.cruise_eas,
            "miss_probability_per_capture": self.miss_probability,
            "k": self.k,
            "model": "e' = -e/tau + w, Dryden w (MIL-F-8785C): sigma_h^2 = sigma_w^2 tau^2 "
            "(r + 2) / (2 (r + 1)^2), r = tau TAS / L_w",
        }


def design_hold(
    turbulence: Turbulence | None,
    autopilot: str,
    cruise_eas: float,
    params: dict[str, float] | None = None,
) -> AltitudeHold | None:
    """The altitude hold a plan designs for: ``turbulence`` (None or still: no allowance)
    through ``autopilot``'s altitude loop at the time constant the vehicle is set to in
    ``params`` (NAME -> value), else as the autopilot ships it."""
    if turbulence is None or not turbulence.present:
        return None
    ap = autopilot_for(autopilot)
    if not ap.altitude_loop:
        raise ValueError(f"no altitude loop is known for {ap.title}")
    name = ap.altitude_loop[0]
    spec = ap.spec(name)
    tau = (params or {}).get(name, spec.default if spec is not None else None)
    if tau is None or not tau > 0.0:
        raise ValueError(f"{name} must be a time constant > 0 s, got {tau!r}")
    return AltitudeHold(turbulence, float(tau), float(cruise_eas), loop_param=name)
