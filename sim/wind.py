"""The air mass the aircraft flies in: a steady wind plus seeded gusts.

Steady wind: ``speed`` m/s from ``from_deg`` (meteorological: the direction it blows FROM,
clockwise from north; 270 is a westerly, blowing towards the east).

Gusts (stated model): a first-order Gauss-Markov process on each horizontal axis, the
continuous form of the Dryden spectrum's first-order longitudinal term (MIL-F-8785C): stationary
standard deviation ``gust`` m/s, correlation time tau = L / V with the scale length L = 533 m
(1,750 ft, MIL-F-8785C above 2,000 ft) and V the cruise airspeed (about 21 s at 25 m/s). Each
step updates it exactly whatever the step's length: u' = u a + sigma sqrt(1 - a^2) n, a =
exp(-dt / tau), n standard normal from the seeded generator. No vertical gusts: the vertical
component only moves the altitude, which the autopilot's TECS holds on its own time constant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs_planner.aircraft.profile import DRYDEN_SCALE_LENGTH_M

_BATCH = 4096


@dataclass(frozen=True)
class WindModel:
    """What a flight's air mass is made of (the draws come from ``seed``)."""

    speed: float = 0.0  # m/s, steady
    from_deg: float = 0.0  # where it blows from, clockwise from north
    gust: float = 0.0  # m/s, standard deviation of each horizontal gust component
    seed: int = 0

    @property
    def still(self) -> bool:
        return self.speed == 0.0 and self.gust == 0.0

    @property
    def steady(self) -> tuple[float, float]:
        """(east, north) m/s the air moves towards."""
        a = math.radians(self.from_deg)
        return -self.speed * math.sin(a), -self.speed * math.cos(a)

    def describe(self) -> str:
        if self.still:
            return "still air"
        out = f"wind {self.speed:g} m/s from {self.from_deg:03.0f} deg"
        if self.gust > 0:
            out += f", gusts {self.gust:g} m/s (first-order Gauss-Markov, L = 533 m)"
        return out


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


@dataclass(frozen=True)
class WindSpec:
    """The wind a dry run flies: ``speed`` m/s from ``from_deg`` (None: a direction drawn per
    flight, uniformly), gusts of ``gust`` m/s."""

    speed: float = 0.0
    from_deg: float | None = None
    gust: float = 0.0

    @property
    def still(self) -> bool:
        return self.speed == 0.0 and self.gust == 0.0

    def draw(self, rng: np.random.Generator) -> WindModel:
        """One flight's air mass: its direction (when not given) and gust seed from ``rng``."""
        direction = float(rng.uniform(0.0, 360.0)) if self.from_deg is None else self.from_deg
        return WindModel(self.speed, direction, self.gust, int(rng.integers(2**31)))

    def describe(self) -> str:
        if self.still:
            return "still air"
        where = f"{self.from_deg:g} deg" if self.from_deg is not None else "drawn directions"
        out = f"wind {self.speed:g} m/s from {where}"
        if self.gust > 0:
            out += f", gusts {self.gust:g} m/s (first-order Gauss-Markov per axis, L = 533 m)"
        return out
