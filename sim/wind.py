"""The air mass the aircraft flies in: a steady wind plus seeded gusts and vertical turbulence.

Steady wind: ``speed`` m/s from ``from_deg`` (meteorological: the direction it blows FROM,
clockwise from north; 270 is a westerly, blowing towards the east).

Gusts (stated model): a first-order Gauss-Markov process on each horizontal axis, the
continuous form of the Dryden spectrum's first-order longitudinal term (MIL-F-8785C): stationary
standard deviation ``gust`` m/s, correlation time tau = L / V with the scale length L = 533 m
(1,750 ft, MIL-F-8785C above 2,000 ft) and V the cruise airspeed (about 21 s at 25 m/s). Each
step updates it exactly whatever the step's length: u' = u a + sigma sqrt(1 - a^2) n, a =
exp(-dt / tau), n standard normal from the seeded generator.

Vertical turbulence (``turbulence``, sim/turbulence.py): the Dryden vertical component of
MIL-F-8785C at its scale length and intensity at the aircraft's altitude, flown through at its
true airspeed, from a generator of its own (seeded from the flight's ``seed``: the horizontal
gusts of a seed are the same with or without it). The air moves the aircraft up and down with
it; the autopilot flies the height error out on its own time constant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gcs_planner.sim.turbulence import (
    Turbulence,
    dryden_step,
    scale_length_w,
    stationary_state,
    vertical_speed,
)

from gcs_planner.aircraft.profile import DRYDEN_SCALE_LENGTH_M

_BATCH = 4096


@dataclass(frozen=True)
class WindModel:
    """What a flight's air mass is made of (the draws come from ``seed``)."""

    speed: float = 0.0  # m/s, steady
    from_deg: float = 0.0  # where it blows from, clockwise from north
    gust: float = 0.0  # m/s, standard deviation of each horizontal gust component
    seed: int = 0
    turbulence: Turbulence | None = None  # vertical (sim/turbulence.py)

    @property
    def turbulent(self) -> bool:
        return self.turbulence is not None and self.turbulence.present

    @property
    def still(self) -> bool:
        return self.speed == 0.0 and self.gust == 0.0 and not self.turbulent

    @property
    def steady(self) -> tuple[float, float]:
        """(east, north) m/s the air moves towards."""
        a = math.radians(self.from_deg)
        return -self.speed * math.sin(a), -self.speed * math.cos(a)

    def describe(self) -> str:
        parts = []
        if self.speed > 0 or self.gust > 0:
            parts.append(f"wind {self.speed:g} m/s from {self.from_deg:03.0f} deg")
        if self.gust > 0:
            parts.append(f"gusts {self.gust:g} m/s (first-order Gauss-Markov, L = 533 m)")
        if self.turbulence is not None and self.turbulent:
            parts.append(self.turbulence.describe())
        return ", ".join(parts) or "still air"


class WindField:
    """The wind one flight meets, advanced step by step (``at`` is called once per step)."""

    def __init__(self, model: WindModel, airspeed: float) -> None:
        self.model = model
        self.wx, self.wy = model.steady
        self.tau = DRYDEN_SCALE_LENGTH_M / max(airspeed, 1.0)
        self.sigma = float(model.gust)
        self.rng = np.random.default_rng(model.seed)
        # Start in the stationary distribution, so the first minutes are as gusty as the rest.
        self.ux = self.uy = 0.0
        if self.sigma > 0:
            self.ux, self.uy = (float(v) for v in self.sigma * self.rng.standard_normal(2))
        self._normals = np.empty(0)
        self._k = 0
        # Vertical turbulence: the Dryden filter's state (sim/turbulence.py), its own draws.
        self.turbulence = model.turbulence if model.turbulent else None
        self.w1 = self.w2 = 0.0
        self._vnormals = np.empty(0)
        self._kv = 0
        if self.turbulence is not None:
            self.vrng = np.random.default_rng([model.seed, 1])
            self.w_alt, self.w_sigma = self.turbulence.table()
            self.w1, self.w2 = stationary_state(*(float(v) for v in self.vrng.standard_normal(2)))

    @property
    def turbulent(self) -> bool:
        return self.turbulence is not None

    @property
    def steady(self) -> bool:
        """Neither gusts nor turbulence: the air changes nothing from step to step."""
        return self.sigma == 0.0 and self.turbulence is None

    def _normal(self) -> float:
        if self._k >= len(self._normals):
            self._normals = self.rng.standard_normal(_BATCH)
            self._k = 0
        self._k += 1
        return float(self._normals[self._k - 1])

    def current(self) -> tuple[float, float]:
        """The wind (east, north m/s) now, without advancing the gusts."""
        return self.wx + self.ux, self.wy + self.uy

    def step(self, dt: float) -> tuple[float, float]:
        """The wind (east, north m/s) over the next ``dt`` seconds."""
        if self.sigma > 0:
            a = math.exp(-dt / self.tau)
            b = self.sigma * math.sqrt(1.0 - a * a)
            self.ux = self.ux * a + b * self._normal()
            self.uy = self.uy * a + b * self._normal()
        return self.wx + self.ux, self.wy + self.uy

    def _vnormal(self) -> float:
        if self._kv >= len(self._vnormals):
            self._vnormals = self.vrng.standard_normal(_BATCH)
            self._kv = 0
        self._kv += 1
        return float(self._vnormals[self._kv - 1])

    def vertical(self, dt: float, altitude_msl: float, tas: float) -> float:
        """The vertical gust (m/s, up) over the next ``dt`` seconds, flown at ``tas`` m/s at
        ``altitude_msl`` m (0 without turbulence, and no draw)."""
        if self.turbulence is None:
            return 0.0
        du = dt * max(tas, 1.0) / scale_length_w(altitude_msl)
        n1 = self._vnormal()
        n2 = self._vnormal()
        self.w1, self.w2 = dryden_step(self.w1, self.w2, du, n1, n2)
        sigma = float(np.interp(altitude_msl, self.w_alt, self.w_sigma))
        return vertical_speed(sigma, self.w1, self.w2)

    def air(self, dt: float, altitude_msl: float, tas: float) -> tuple[float, float, float]:
        """The air's motion (east, north, up m/s) over the next ``dt`` seconds: ``step`` and
        ``vertical``."""
        wx, wy = self.step(dt)
        return wx, wy, self.vertical(dt, altitude_msl, tas)


@dataclass(frozen=True)
class WindSpec:
    """The wind a dry run flies: ``speed`` m/s from ``from_deg`` (None: a direction drawn per
    flight, uniformly), gusts of ``gust`` m/s."""

    speed: float = 0.0
    from_deg: float | None = None
    gust: float = 0.0
    turbulence: Turbulence | None = None

    @property
    def turbulent(self) -> bool:
        return self.turbulence is not None and self.turbulence.present

    @property
    def still(self) -> bool:
        return self.speed == 0.0 and self.gust == 0.0 and not self.turbulent

    def draw(self, rng: np.random.Generator) -> WindModel:
        """One flight's air mass: its direction (when not given) and gust seed from ``rng``."""
        direction = float(rng.uniform(0.0, 360.0)) if self.from_deg is None else self.from_deg
        turbulence = self.turbulence if self.turbulent else None
        return WindModel(self.speed, direction, self.gust, int(rng.integers(2**31)), turbulence)

    def describe(self) -> str:
        parts = []
        if self.speed > 0 or self.gust > 0:
            where = f"{self.from_deg:g} deg" if self.from_deg is not None else "drawn directions"
            parts.append(f"wind {self.speed:g} m/s from {where}")
        if self.gust > 0:
            parts.append(f"gusts {self.gust:g} m/s (first-order Gauss-Markov per axis, L = 533 m)")
        if self.turbulence is not None and self.turbulent:
            parts.append(self.turbulence.describe())
        return ", ".join(parts) or "still air"
