"""The point mass of sim/aircraft.py compiled (numba), for the compiled flight
(sim/flight_kernel.py): EAS2TAS of sim/atmosphere.py, ``arc_step`` and ``step`` (the bank rolling
towards the one asked, in substeps), with the same formulas in the same order.

A state is the flight's state vector (sim/flight_records.py ``S_*``); a step writes the new
state's aircraft fields (the first ``AIRCRAFT_SIZE``) into ``out``. (After editing this module
clear the cached ``fly_plain``: see sim/navigator_kernel.py.)
"""

from __future__ import annotations

import math

import numpy as np
from gcs_planner.sim import atmosphere
from gcs_planner.sim.flight_records import (
    S_BANK,
    S_CLIMB,
    S_COURSE,
    S_GS,
    S_HEADING,
    S_T,
    S_TAS,
    S_X,
    S_Y,
    S_Z,
    Aircraft,
)
from numba import njit

from gcs_planner.aircraft.profile import G

_SIGMA11 = atmosphere._SIGMA11
_T11 = atmosphere._T11


@njit(cache=True)
def wrap(a: float) -> float:
    """The angle ``a`` (rad) in [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


@njit(cache=True)
def eas2tas(altitude_m: float) -> float:
    """sim/atmosphere.py eas2tas."""
    h = max(altitude_m, 0.0)
    if h <= atmosphere.TROPOPAUSE_M:
        ratio = (1.0 - atmosphere.LAPSE_K_PER_M * h / atmosphere.T0_K) ** atmosphere._EXPONENT
    else:
        ratio = _SIGMA11 * math.exp(
            -atmosphere.G0 * (h - atmosphere.TROPOPAUSE_M) / (atmosphere.R_AIR * _T11)
        )
    return 1.0 / math.sqrt(ratio)


@njit(cache=True)
def max_lateral(bank_deg: float) -> float:
    """The lateral acceleration (m/s^2) of a coordinated turn at ``bank_deg``."""
    return G * math.tan(math.radians(bank_deg))


@njit(cache=True)
def arc_step(s: np.ndarray, aircraft: Aircraft, lateral: float, climb: float, dt: float,
             wx: float, wy: float, wz: float, e2t: float, limit: float,
             out: np.ndarray) -> None:  # fmt: skip
    """sim/aircraft.py arc_step, for an aircraft with a turn limit (``limit``: its largest
    lateral acceleration, max_lateral of its roll limit), through air moving at (wx, wy, wz)
    (east, north, up); writes the new state's aircraft fields into ``out``, which may be ``s``
    (each field is read before it is written)."""
    v = aircraft.airspeed * e2t
    psi0 = s[S_HEADING]
    if aircraft.ground_speed_floor > 0.0:  # sim/aircraft.py Envelope.held_tas
        short = aircraft.ground_speed_floor - (v + wx * math.cos(psi0) + wy * math.sin(psi0))
        if short > 0.0:
            v = max(v, min(v + short, aircraft.airspeed_max * e2t))
    vz = min(max(climb, -aircraft.sink_rate), aircraft.climb_rate)
    if aircraft.pitch_limit < 90.0:
        vz = min(vz, v * math.sin(math.radians(aircraft.pitch_limit)))
    vh = math.sqrt(max(v * v - vz * vz, 0.0))
    a = min(max(lateral, -limit), limit)
    w = a / v
    if abs(w) < 1e-9:
        psi1 = psi0
        dx = vh * dt * math.cos(psi0)
        dy = vh * dt * math.sin(psi0)
    else:
        psi1 = psi0 + w * dt
        dx = vh / w * (math.sin(psi1) - math.sin(psi0))
        dy = -vh / w * (math.cos(psi1) - math.cos(psi0))
    gx, gy = vh * math.cos(psi1) + wx, vh * math.sin(psi1) + wy
    out[S_X] = s[S_X] + dx + wx * dt
    out[S_Y] = s[S_Y] + dy + wy * dt
    out[S_Z] = s[S_Z] + vz * dt + wz * dt
    out[S_COURSE] = math.atan2(gy, gx)
    out[S_T] = s[S_T] + dt
    out[S_BANK] = -math.degrees(math.atan(a / G))
    out[S_CLIMB] = vz + wz
    out[S_HEADING] = wrap(psi1)
    out[S_TAS] = v
    out[S_GS] = math.hypot(gx, gy)


@njit(cache=True)
def step(s: np.ndarray, aircraft: Aircraft, lateral: float, climb: float, dt: float, wx: float,
         wy: float, wz: float, e2t: float, limit: float, out: np.ndarray) -> None:  # fmt: skip
    """sim/aircraft.py step (the bank rolling towards the one asked, in substeps), for an
    aircraft with a turn limit, through air moving at (wx, wy, wz); writes the new state's
    aircraft fields into ``out``."""
    bank_limit = aircraft.bank_limit
    tau = aircraft.roll_tau
    asked = min(max(-math.degrees(math.atan(lateral / G)), -bank_limit), bank_limit)
    n = max(1, math.ceil(dt / aircraft.roll_substep - 1e-9))
    h = dt / n
    keep = 1.0 - math.exp(-h / tau)
    most = aircraft.roll_rate * h
    bank = s[S_BANK]
    gap = bank - asked
    if (aircraft.roll_settled < abs(gap) <= aircraft.roll_rate * tau
            and abs(gap) * dt <= aircraft.roll_one_arc):  # fmt: skip
        decay = math.exp(-dt / tau)
        mean = asked + gap * tau * (1.0 - decay) / dt
        arc_step(s, aircraft, -G * math.tan(math.radians(mean)), climb, dt, wx, wy, wz, e2t,
                 limit, out)  # fmt: skip
        out[S_BANK] = asked + gap * decay
        return
    src = s
    for i in range(n):
        if abs(asked - bank) <= aircraft.roll_settled:
            arc_step(src, aircraft, lateral, climb, dt - i * h, wx, wy, wz, e2t, limit, out)
            return
        bank += min(max((asked - bank) * keep, -most), most)
        arc_step(src, aircraft, -G * math.tan(math.radians(bank)), climb, h, wx, wy, wz, e2t,
                 limit, out)  # fmt: skip
        src = out
