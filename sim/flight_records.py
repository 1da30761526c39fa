"""The records the compiled flight (sim/flight_kernel.py) reads, and the slots of the arrays it
writes in place (numba types a NamedTuple as a record).

What the flight reads is made from what it describes: the aircraft from its envelope
(:func:`aircraft_record`), the gusts from the wind field (:func:`gusts_record`), the INS from
the estimate (:func:`ins_record`); the autopilot's rules, the flight's step and limits and the
mission's commands from the navigator (sim/navigators/compiled.py). Where a part is absent (no
gusts, no INS) a record of the same dtypes stands for it (``sigma`` 0, ``present`` False): the
kernel is then compiled once, not once per combination.

What the flight writes in place stays arrays, their slots named here once: the flight's state
(read and written every step, ``S_*``), the samples (the navigator's track rows, in the order
of sim/navigators/state.py ``SAMPLE_FIELDS``) and the decisions (``E_*``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from gcs_planner.sim.aircraft import (
    ROLL_ONE_ARC_DEG_S,
    ROLL_RATE_DEG_S,
    ROLL_SETTLED_DEG,
    ROLL_SUBSTEP_S,
    ROLL_TAU_S,
    Envelope,
)
from gcs_planner.sim.ins import InsEstimate
from gcs_planner.sim.wind import WindField

# Why the kernel stopped.
STOP_EVENT = 0  # the next step is not plain: the Python navigator flies it
STOP_FULL = 1  # the sample buffer is full: call again
STOP_TIME = 2  # the time limit is reached

# What the kernel flies of the active command.
MODE_TRACK = 0  # tracking the waypoint
MODE_ALTITUDE_LOITER = 1  # circling the waypoint for its altitude

# The flight's state (in and out): the aircraft's (sim/aircraft.py AircraftState, in its
# order), the navigator's glide slope and track (min_dist, alt_error, settled), the gusts' (the
# wind field's ux, uy), the metres flown (the INS's distance) and the vertical turbulence's
# filter (the wind field's w1, w2: sim/turbulence.py).
S_X, S_Y, S_Z, S_COURSE, S_T, S_BANK, S_CLIMB, S_HEADING, S_TAS, S_GS = range(10)
S_MIN_DIST, S_ALT_ERROR, S_SETTLED, S_UX, S_UY, S_DISTANCE = range(10, 16)
S_W1, S_W2 = range(16, 18)
STATE_SIZE = 18
AIRCRAFT_SIZE = 10  # the aircraft's fields, first

# The decisions the kernel made (out), one row each: when, the sample row, the item's seq,
# what, and the figure the navigator's event text gives.
E_T, E_SAMPLE, E_SEQ, E_KIND, E_VALUE = range(5)
EVENT_SIZE = 5
EVENT_NONE = -1
EVENT_WITHIN = 0  # reached within the acceptance radius (value: the distance)
EVENT_PASSED = 1  # reached past the finish line (value: the distance)
EVENT_ALTITUDE = 2  # at the waypoint off its altitude, circling it (value: how far off)
EVENT_ALTITUDE_REACHED = 3  # leaves the altitude loiter of a waypoint


class Aircraft(NamedTuple):
    """The point mass (sim/aircraft.py ``step``): its envelope and how it rolls into a turn."""

    airspeed: float  # m/s, equivalent
    bank_limit: float  # deg
    climb_rate: float  # m/s
    sink_rate: float  # m/s
    pitch_limit: float  # deg (>= 90: none)
    roll_tau: float  # s
    roll_rate: float  # deg/s
    roll_substep: float  # s
    roll_settled: float  # deg
    roll_one_arc: float  # deg s
    ground_speed_floor: float  # m/s (0: none): sim/aircraft.py ``Envelope.held_tas``
    airspeed_max: float  # m/s, equivalent: the most the floor raises the airspeed to


def aircraft_record(env: Envelope) -> Aircraft:
    """The aircraft flying within ``env``, rolling as sim/aircraft.py does."""
    return Aircraft(
        float(env.airspeed),
        float(env.bank_limit_deg),
        float(env.climb_rate),
        float(env.sink_rate),
        float(env.pitch_limit_deg),
        float(ROLL_TAU_S),
        float(ROLL_RATE_DEG_S),
        float(ROLL_SUBSTEP_S),
        float(ROLL_SETTLED_DEG),
        float(ROLL_ONE_ARC_DEG_S),
        float(env.ground_speed_floor),
        float(min(env.airspeed_max, 1e9)),
    )


class Rules(NamedTuple):
    """The autopilot's waypoint rules (the traits of its record, gcs_planner/aircraft/autopilot.py)
    and the parameters they read (sim/navigators/params.py ``AutopilotParams``)."""

    # The acceptance radius is the larger of NAV_ACC_RAD and npfg's switch distance, and a leg
    # from its own waypoint has no finish line to pass (PX4); else the acceptance radius is the
    # item's param2 or the L1 turn distance (ArduPlane).
    switches_early: bool
    # A waypoint counts only within NAV_FW_ALT_RAD of its altitude; off it, the aircraft
    # circles it on the loiter radius until the altitude is in (PX4).
    circles_for_altitude: bool
    # The altitude target reaches the waypoint's max(acceptance, |loiter radius|) before it
    # (PX4); else at the waypoint (ArduPlane's glide slope).
    climbs_at_once: bool
    acceptance_radius: float  # m: PX4 NAV_ACC_RAD
    wp_radius: float  # m: ArduPlane WP_RADIUS
    loiter_radius: float  # m, signed: + clockwise
    npfg_period: float  # s
    npfg_damping: float
    npfg_switch_multiplier: float
    altitude_time_constant: float  # s: TECS_TIME_CONST / FW_T_ALT_TC


class Flight(NamedTuple):
    """What holds over one call of the kernel: the aircraft, the autopilot's rules, the step,
    the time limit and the altitude of the local frame's origin (for EAS2TAS)."""

    aircraft: Aircraft
    rules: Rules
    dt: float  # s
    time_limit: float  # s
    alt_offset: float  # m above sea level of z = 0


class Commands(NamedTuple):
    """The mission's commands, one entry per navigator command: its position, ArduPlane's
    acceptance radius (param2, 0: none), seq, the next waypoint it flies to, and whether it is a
    plain waypoint (a NAV_WAYPOINT with a position that the autopilot flies: the kernel may reach
    it and advance onto it; any other item is reached, skipped or flown by the Python
    navigator)."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    acceptance: np.ndarray
    seq: np.ndarray  # int64
    has_next: np.ndarray  # bool
    next_x: np.ndarray
    next_y: np.ndarray
    plain: np.ndarray  # bool


class Gusts(NamedTuple):
    """The wind field (sim/wind.py ``WindField``): the steady wind (east, north m/s), the gusts'
    time constant and strength (``sigma`` 0: none) and the batch of normal draws they take; the
    vertical turbulence (``turbulent``, sim/turbulence.py): its intensity against altitude
    (``w_alt`` m, ``w_sigma`` m/s) and its own batch of draws."""

    tau: float
    sigma: float
    wx: float
    wy: float
    normals: np.ndarray
    turbulent: bool
    w_alt: np.ndarray
    w_sigma: np.ndarray
    vnormals: np.ndarray


class Ins(NamedTuple):
    """The INS estimate (sim/ins.py ``InsEstimate``, ``present`` False: none): its error's state
    and the landmarks it has not used yet, (n, 3) sorted by x."""

    present: bool
    scale: float
    v0: float
    v_at: float
    h0: float
    h_at: float
    v_sign: float
    h_dir: float
    capture: float
    landmarks: np.ndarray


_EMPTY = np.empty(0)
_EMPTY_XYZ = np.empty((0, 3))
NO_GUSTS = Gusts(0.0, 0.0, 0.0, 0.0, _EMPTY, False, _EMPTY, _EMPTY, _EMPTY)
NO_INS = Ins(False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, _EMPTY_XYZ)


def gusts_record(wind: WindField | None) -> tuple[Gusts, int, int]:
    """The wind field as the kernel reads it, and the indices of its next normal draws: the
    gusts' and the vertical turbulence's."""
    if wind is None:
        return NO_GUSTS, 0, 0
    if wind.turbulent:
        vertical = (True, wind.w_alt, wind.w_sigma, wind._vnormals)
    else:
        vertical = (False, _EMPTY, _EMPTY, _EMPTY)
    gusts = Gusts(float(wind.tau), float(wind.sigma), float(wind.wx), float(wind.wy),
                  wind._normals, *vertical)  # fmt: skip
    return gusts, int(wind._k), int(wind._kv)


def resume_gusts(wind: WindField, state: np.ndarray, k: int, kv: int) -> None:
    """The wind field after the kernel flew its gusts and its turbulence to ``state``'s, their
    next draws ``k`` and ``kv``."""
    wind.ux, wind.uy, wind._k = float(state[S_UX]), float(state[S_UY]), k
    if wind.turbulent:
        wind.w1, wind.w2, wind._kv = float(state[S_W1]), float(state[S_W2]), kv


def ins_busy(ins: InsEstimate) -> bool:
    """A landmark is being passed (its correction comes once the pass ends) or the flight is
    lost: the Python navigator flies."""
    return bool(ins._passes) or ins.lost


def ins_record(ins: InsEstimate | None, cache: dict) -> Ins:
    """The INS as the kernel reads it; its unused landmarks cached in ``cache`` per count of
    used ones."""
    if ins is None:
        return NO_INS
    return Ins(
        True,
        float(ins.scale),
        float(ins.v0),
        float(ins.v_at),
        float(ins.h0),
        float(ins.h_at),
        float(ins.v_sign),
        float(ins.h_dir),
        float(ins.capture),
        _landmarks(ins, cache),
    )


def _landmarks(ins: InsEstimate, cache: dict) -> np.ndarray:
    """The V and H landmarks the INS has not used yet, (n, 3) sorted by x, cached per count of
    used ones."""
    used = ins._used
    key = len(used)
    if cache.get("key") != key:
        idx = [li for cell in ins._grid.values() for li in cell if li not in used]
        cache["key"] = key
        xyz = np.asarray(ins.scenario.xyz[sorted(idx)], dtype=float).reshape(-1, 3)
        cache["xyz"] = np.ascontiguousarray(xyz[np.argsort(xyz[:, 0], kind="stable")])
    return cache["xyz"]
