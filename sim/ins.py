"""The INS in flight: the estimate the autopilot steers, and the corrections the truth makes.

Error model (docs/model.md, "Flight in the real world" and "Error model"): every metre flown adds
delta error units to each component, one unit being ``error_unit`` metres of position (0.1 m
by default: the paper's Table 2 is in decimetres). The vertical error displaces the estimate up
or down, the horizontal one in a horizontal direction the aircraft does not know; both are drawn
(seeded) at the start and after each reset of that component. So the estimate is the true
position plus (h cos b, h sin b, s v) * error_unit * delta, v and h the metres flown since the
component's last reset (or its residual after a failed correction).

The autopilot steers that estimate (sim/navigators/base.py); a correction happens only where the
TRUE track passes within ``capture_radius`` (3D) of a correction landmark of the vehicle's own
database not used yet, at the closest approach of that pass (the landmark is used once). There
the limits of its kind must hold (else the vehicle is lost: the flight ends), then the landmark
corrects its component: a reliable one, or an unreliable one with probability p (drawn), resets
it to 0 and draws a new direction; a failed one leaves min(error, residual).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gcs_planner.sim.aircraft import AircraftState

from gcs_planner.scenario.model import Kind, Parameters, Scenario

DEFAULT_ERROR_UNIT_M = 0.1
_CELL_M = 1000.0


@dataclass(frozen=True)
class InsCorrection:
    """One correction landmark the true track passed within the capture radius of."""

    landmark: int
    id: str
    kind: Kind
    unreliable: bool
    distance: float  # flown from A to the closest approach
    miss: float  # true 3D closest approach, metres
    v_before_m: float  # metres flown's worth of error on arrival (before the correction)
    h_before_m: float
    estimate_error_m: float  # how far the estimate was from the truth there, metres
    within_limits: bool
    succeeded: bool | None  # None: lost on arrival
    v_after_m: float
    h_after_m: float


# The landmark grid of the last scenario flown: a Monte Carlo builds its INS once per flight.
_GRID_CACHE: list[tuple[Scenario, dict[tuple[int, int], list[int]]]] = []


def _landmark_grid(scenario: Scenario) -> dict[tuple[int, int], list[int]]:
    """The scenario's V and H landmarks by _CELL_M square (read only)."""
    if _GRID_CACHE and _GRID_CACHE[0][0] is scenario:
        return _GRID_CACHE[0][1]
    grid: dict[tuple[int, int], list[int]] = {}
    mask = (scenario.kind == Kind.V) | (scenario.kind == Kind.H)
    for i in np.flatnonzero(mask):
        x, y = scenario.xyz[i, 0], scenario.xyz[i, 1]
        grid.setdefault((int(x // _CELL_M), int(y // _CELL_M)), []).append(int(i))
    _GRID_CACHE[:] = [(scenario, grid)]
    return grid


class InsEstimate:
    """The INS of one flight (one seeded draw of directions and outcomes)."""

    def __init__(
        self,
        scenario: Scenario,
        params: Parameters,
        rng: np.random.Generator,
        *,
        capture_radius: float,
        error_unit: float = DEFAULT_ERROR_UNIT_M,
    ) -> None:
        self.scenario = scenario
        self.params = params
        self.rng = rng
        self.capture = float(capture_radius)
        self.scale = params.delta * error_unit  # metres of position per metre flown
        self.distance = 0.0
        # Each component: (value in metres flown at its last reset, distance of that reset).
        self.v0, self.v_at = 0.0, 0.0
        self.h0, self.h_at = 0.0, 0.0
        self.v_sign = 1.0 if rng.random() < 0.5 else -1.0
        self.h_dir = float(rng.uniform(0.0, 2.0 * math.pi))
        self.corrections: list[InsCorrection] = []
        self.lost = False
        self._passes: dict[int, tuple[float, float]] = {}  # landmark -> (best miss, distance)
        self._used: set[int] = set()
        self._grid = _landmark_grid(scenario)

    # The estimate -------------------------------------------------------------------------
    def errors_m(self, distance: float | None = None) -> tuple[float, float]:
        """(v, h) in metres flown's worth of error at ``distance`` flown (default now)."""
        d = self.distance if distance is None else distance
        return self.v0 + (d - self.v_at), self.h0 + (d - self.h_at)

    def offset(self, s: AircraftState) -> tuple[float, float, float]:
        v, h = self.errors_m()
        dh = h * self.scale
        return dh * math.cos(self.h_dir), dh * math.sin(self.h_dir), self.v_sign * v * self.scale

    # The truth ----------------------------------------------------------------------------
    def observe(self, before: AircraftState, after: AircraftState) -> None:
        """The true track flew ``before`` -> ``after``: count the metres, find the passes."""
        # The metres flown summed in plain floats, in the order sim/flight_kernel.py sums them,
        # so that the compiled flight's estimate is the same to the last bit.
        dx, dy, dz = after.x - before.x, after.y - before.y, after.z - before.z
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        d0 = self.distance
        self.distance += length
        if self.lost:
            return
        p0 = np.array((before.x, before.y, before.z))
        seg = np.array((dx, dy, dz))
        r = self.capture
        near: set[int] = set()
        for li in self._candidates(before, after):
            rel = self.scenario.xyz[li] - p0
            t = 0.0 if length <= 0 else min(max(float(rel @ seg) / (length * length), 0.0), 1.0)
            miss = float(np.linalg.norm(rel - t * seg))
            if miss <= r:
                near.add(li)
                best = self._passes.get(li)
                if best is None or miss < best[0]:
                    self._passes[li] = (miss, d0 + t * length)
        for li in [k for k in self._passes if k not in near]:
            self._correct(li)
            if self.lost:
                return

    def finish(self) -> None:
        """The flight is over: passes still open end here."""
        for li in list(self._passes):
            if self.lost:
                return
            self._correct(li)

    def _candidates(self, a: AircraftState, b: AircraftState) -> list[int]:
        r = self.capture
        x0, x1 = sorted((a.x, b.x))
        y0, y1 = sorted((a.y, b.y))
        out: list[int] = []
        for i in range(int((x0 - r) // _CELL_M), int((x1 + r) // _CELL_M) + 1):
            for j in range(int((y0 - r) // _CELL_M), int((y1 + r) // _CELL_M) + 1):
                for li in self._grid.get((i, j), ()):
                    if li not in self._used:
                        out.append(li)
        return out

    def _correct(self, li: int) -> None:
        miss, d = self._passes.pop(li)
        self._used.add(li)
        p = self.params
        kind = Kind(int(self.scenario.kind[li]))
        unreliable = bool(self.scenario.unreliable[li])
        v, h = self.errors_m(d)
        est = self.scale * math.hypot(v, h)
        v_lim, h_lim = p.limits_m(kind)
        ok = v <= v_lim and h <= h_lim
        succeeded: bool | None = None
        if ok:
            succeeded = (not unreliable) or bool(self.rng.random() < p.p_success)
            if kind == Kind.V:
                self.v0, self.v_at = (0.0 if succeeded else min(v, p.residual_m)), d
                self.v_sign = 1.0 if self.rng.random() < 0.5 else -1.0
            else:
                self.h0, self.h_at = (0.0 if succeeded else min(h, p.residual_m)), d
                self.h_dir = float(self.rng.uniform(0.0, 2.0 * math.pi))
        v_after, h_after = self.errors_m(d)
        self.corrections.append(
            InsCorrection(li, self.scenario.ids[li], kind, unreliable, d, miss, v, h, est, ok,
                          succeeded, v_after, h_after)
        )  # fmt: skip
        if not ok:
            self.lost = True
