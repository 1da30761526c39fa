"""The navigators' formulas compiled (numba), for the compiled flight (sim/flight_kernel.py): the
acceptance radius, the glide slope, L1 on the line and on the circle, the gusts and the vertical
turbulence, the INS estimate's offset, and the decisions between plain waypoints, each with the
same formulas in the same order as the Python navigator it names (sim/navigators/), so the
flights are the same.

The autopilot's rules are read from its record's traits (sim/flight_records.py ``Rules``), the
mission's commands from ``Commands``, the flight's state from its vector (``S_*``).

Each is inlined into the flight's loop (numba's ``inline="always"``, in its IR): the loop is
compiled as one function rather than linked from one per formula, which numba compiles slower.

numba's cache is keyed by each kernel's own source file: after editing this module (or
sim/point_mass_kernel.py) the cached ``fly_plain`` still holds the old code until
sim/flight_kernel.py changes; clear the ``sim/__pycache__/*.nbi``/``*.nbc`` files.
"""

from __future__ import annotations

import math

import numpy as np
from gcs_planner.sim.flight_records import (
    AIRCRAFT_SIZE,
    E_KIND,
    E_SAMPLE,
    E_SEQ,
    E_T,
    E_VALUE,
    EVENT_ALTITUDE,
    EVENT_ALTITUDE_REACHED,
    EVENT_NONE,
    EVENT_PASSED,
    EVENT_WITHIN,
    S_ALT_ERROR,
    S_BANK,
    S_CLIMB,
    S_COURSE,
    S_DISTANCE,
    S_GS,
    S_HEADING,
    S_MIN_DIST,
    S_SETTLED,
    S_T,
    S_TAS,
    S_UX,
    S_UY,
    S_W1,
    S_W2,
    S_X,
    S_Y,
    S_Z,
    Commands,
    Flight,
    Gusts,
    Ins,
    Rules,
)
from gcs_planner.sim.navigators.base import COARSE_STEPS
from gcs_planner.sim.navigators.px4 import (
    ALTITUDE_ACCEPTANCE_M,
    EXIT_COURSE_DEG,
    EXIT_REACHABLE,
    SWITCH_DISTANCE_CAP_M,
)
from gcs_planner.sim.navigators.steering import L1_DAMPING, L1_PERIOD_S
from gcs_planner.sim.point_mass_kernel import wrap
from gcs_planner.sim.turbulence import SQRT3
from gcs_planner.sim.turbulence import dryden_step as _dryden_step_py
from gcs_planner.sim.turbulence import scale_length_w as _scale_length_w_py
from numba import njit


@njit(cache=True, inline="always")
def altitude_gain_dt(flight: Flight) -> float:
    """Navigator._altitude_gain_dt: the time over which an altitude error is flown out."""
    return max(flight.rules.altitude_time_constant, flight.dt)


@njit(cache=True, inline="always")
def acceptance(
    ground_speed: float, rules: Rules, cmds: Commands, j: int, prev: np.ndarray, e2t: float
) -> float:
    """ArduPlaneNavigator.acceptance / PX4Navigator.acceptance of command ``j`` on the leg from
    ``prev`` (``e2t`` at the state's altitude)."""
    vg = max(ground_speed, 1e-3)
    if rules.switches_early:
        time_const = rules.npfg_period * rules.npfg_damping
        bound = vg * time_const if vg > 1.0 else 0.5 * time_const * (vg * vg + 1.0)
        switch = min(SWITCH_DISTANCE_CAP_M, bound * rules.npfg_switch_multiplier)
        return max(rules.acceptance_radius, switch)
    if cmds.acceptance[j] > 0:
        return cmds.acceptance[j]
    l1 = L1_DAMPING * L1_PERIOD_S * vg / math.pi
    turn = 90.0
    if cmds.has_next[j]:
        a1 = math.atan2(cmds.y[j] - prev[1], cmds.x[j] - prev[0])
        a2 = math.atan2(cmds.next_y[j] - cmds.y[j], cmds.next_x[j] - cmds.x[j])
        turn = min(abs(math.degrees(wrap(a2 - a1))), 90.0)
    return min(rules.wp_radius * e2t * e2t, l1) * turn / 90.0


@njit(cache=True, inline="always")
def l1_line(ex: float, ey: float, course: float, vg: float, l1: float, kk: float, ax: float,
            ay: float, cx: float, cy: float) -> tuple[float, float]:  # fmt: skip
    """Navigator.l1_line on (ax, ay) -> (cx, cy) from the estimate (ex, ey): (lateral
    acceleration, settled 1.0 or 0.0)."""
    abx, aby = cx - ax, cy - ay
    nrm = math.hypot(abx, aby)
    if nrm < 1e-6:
        abx, aby = cx - ex, cy - ey
        nrm = math.hypot(abx, aby) or 1.0
    ux, uy = abx / nrm, aby / nrm
    rx, ry = ex - ax, ey - ay
    ccx, ccy = math.cos(course), math.sin(course)
    dist_a = math.hypot(rx, ry)
    along = rx * ux + ry * uy
    settled = 0.0
    if dist_a > l1 and along < -0.7071 * dist_a:
        nu = wrap(math.atan2(-ry, -rx) - course)
    else:
        xtrack = ux * ry - uy * rx
        nu1 = math.asin(max(-0.7071, min(0.7071, xtrack / l1)))
        eta = math.atan2(ux * ccy - uy * ccx, ux * ccx + uy * ccy)
        nu = -(nu1 + eta)
        settled = 1.0 if abs(xtrack) < 0.5 and abs(eta) < 0.005 else 0.0
    nu = max(-math.pi / 2, min(math.pi / 2, nu))
    return kk * vg * vg / l1 * math.sin(nu), settled


@njit(cache=True, inline="always")
def track_demand(state: np.ndarray, flight: Flight, cmds: Commands, j: int, prev: np.ndarray,
                 ex: float, ey: float, ez: float, dist: float, acc: float,
                 gusty: bool) -> tuple[float, float, float, float, float, float]:  # fmt: skip
    """What Navigator.tick asks tracking command ``j`` from the leg's start ``prev``: the glide
    slope's climb, L1's lateral acceleration and the step, coarse on a settled leg in steady
    air; (lateral, climb, step, min_dist, alt_error, settled)."""
    rules, aircraft = flight.rules, flight.aircraft
    cx, cy, cz = cmds.x[j], cmds.y[j], cmds.z[j]
    ax, ay, az = prev[0], prev[1], prev[2]
    vg = max(state[S_GS], 1e-3)
    l1 = L1_DAMPING * L1_PERIOD_S * vg / math.pi
    kk = 4.0 * L1_DAMPING * L1_DAMPING
    gain = altitude_gain_dt(flight)
    min_dist, alt_error = state[S_MIN_DIST], state[S_ALT_ERROR]
    # Navigator.glide from the leg's start.
    end_dist = max(acc, abs(rules.loiter_radius)) if rules.climbs_at_once else 0.0
    total = math.hypot(cx - ax, cy - ay)
    span = total - end_dist
    if span <= 1e-6:
        climb = (cz - ez) / gain
    else:
        min_dist = min(min_dist, dist, total)
        progress = min(max((total - min_dist) / span, 0.0), 1.0)
        target = az + (cz - az) * progress
        alt_error = target - ez
        slope = (cz - az) / span
        # Navigator.glide: no feed-forward before the ramp starts
        ff = vg * slope if 0.0 < progress < 1.0 else 0.0
        climb = ff + (target - ez) / gain
    lateral, settled = l1_line(ex, ey, state[S_COURSE], vg, l1, kk, ax, ay, cx, cy)
    dt = flight.dt
    coarse = dt * COARSE_STEPS
    if (
        settled > 0
        and not gusty
        and abs(alt_error) < 0.5
        and dist > 3.0 * vg * coarse
        and -aircraft.sink_rate < climb < aircraft.climb_rate
    ):
        dt = coarse
        # Navigator.tick: the altitude error flown out over the coarse step.
        climb += alt_error * (-math.expm1(-coarse / gain) / coarse - 1.0 / gain)
    return lateral, climb, dt, min_dist, alt_error, settled


@njit(cache=True, inline="always")
def loiter_radius(state: np.ndarray, rules: Rules, limit: float) -> tuple[float, int]:
    """Navigator.loiter_geometry of a waypoint circled for its altitude: (radius, direction)."""
    lr = rules.loiter_radius
    radius = max(abs(lr), state[S_TAS] * state[S_TAS] / limit)
    return radius, (-1 if lr >= 0 else 1)


@njit(cache=True, inline="always")
def altitude_loiter_demand(state: np.ndarray, flight: Flight, cmds: Commands, j: int, ex: float,
                           ey: float, ez: float, limit: float) -> tuple[float, float]:  # fmt: skip
    """What the navigator asks circling waypoint ``j`` on the loiter radius for its altitude
    (Navigator._tick_altitude_loiter: Navigator.circle, climbing to it); (lateral, climb)."""
    cx, cy, cz = cmds.x[j], cmds.y[j], cmds.z[j]
    vg = max(state[S_GS], 1e-3)
    l1 = L1_DAMPING * L1_PERIOD_S * vg / math.pi
    kk = 4.0 * L1_DAMPING * L1_DAMPING
    radius, direction = loiter_radius(state, flight.rules, limit)
    rx, ry = ex - cx, ey - cy
    r = math.hypot(rx, ry)
    theta = math.atan2(ry, rx)
    intercept = math.atan((r - radius) / (0.5 * l1))
    want = theta + direction * (math.pi / 2 + intercept)
    err = wrap(want - state[S_COURSE])
    ff = direction * vg * vg / radius if radius > 0 and abs(r - radius) < l1 else 0.0
    lateral = ff + kk * vg * vg / l1 * math.sin(max(-math.pi / 2, min(math.pi / 2, err)))
    return lateral, (cz - ez) / altitude_gain_dt(flight)


@njit(cache=True, inline="always")
def gust(ux: float, uy: float, gusts: Gusts, dt: float, k: int) -> tuple[float, float, int]:
    """WindField.step's gusts over ``dt`` from (ux, uy), drawing from ``k`` on: (ux, uy, next
    draw)."""
    if gusts.sigma > 0:
        a = math.exp(-dt / gusts.tau)
        b = gusts.sigma * math.sqrt(1.0 - a * a)
        ux = ux * a + b * gusts.normals[k]
        uy = uy * a + b * gusts.normals[k + 1]
        k += 2
    return ux, uy, k


# The Dryden filter's step and its scale length compiled from their one statement each
# (sim/turbulence.py, which the Python navigator runs): the two paths fly the same formulas
# because they are one function.
dryden_step = njit(cache=True, inline="always")(_dryden_step_py)
scale_length_w = njit(cache=True, inline="always")(_scale_length_w_py)


@njit(cache=True, inline="always")
def vertical_gust(w1: float, w2: float, gusts: Gusts, dt: float, kv: int, altitude_msl: float,
                  tas: float) -> tuple[float, float, float, int]:  # fmt: skip
    """WindField.vertical over ``dt`` at ``altitude_msl`` and ``tas`` from the filter's state
    (w1, w2), drawing from ``kv`` on: (w1, w2, the vertical gust m/s up, next draw)."""
    if not gusts.turbulent:
        return w1, w2, 0.0, kv
    du = dt * max(tas, 1.0) / scale_length_w(altitude_msl)
    w1, w2 = dryden_step(w1, w2, du, gusts.vnormals[kv], gusts.vnormals[kv + 1])
    sigma = np.interp(altitude_msl, gusts.w_alt, gusts.w_sigma)
    return w1, w2, sigma * (SQRT3 * w1 + (1.0 - SQRT3) * w2), kv + 2


@njit(cache=True, inline="always")
def offset(ins: Ins, distance: float, cos_h: float, sin_h: float) -> tuple[float, float, float]:
    """InsEstimate.offset at ``distance`` flown (0 without an INS); ``cos_h``, ``sin_h`` of the
    error's direction."""
    if not ins.present:
        return 0.0, 0.0, 0.0
    v = ins.v0 + (distance - ins.v_at)
    h = ins.h0 + (distance - ins.h_at)
    dh = h * ins.scale
    return dh * cos_h, dh * sin_h, ins.v_sign * v * ins.scale


@njit(cache=True, inline="always")
def flown(s0: np.ndarray, s1: np.ndarray) -> float:
    """The metres flown at s1, flown s0 -> s1 (in the order InsEstimate.observe sums them)."""
    sx, sy, sz = s1[S_X] - s0[S_X], s1[S_Y] - s0[S_Y], s1[S_Z] - s0[S_Z]
    return s0[S_DISTANCE] + math.sqrt(sx * sx + sy * sy + sz * sz)


@njit(cache=True, inline="always")
def near_landmark(s0: np.ndarray, s1: np.ndarray, landmarks: np.ndarray, r: float) -> bool:
    """InsEstimate.observe's test: the true segment s0 -> s1 passes within ``r`` of a landmark
    (``landmarks`` sorted by x: only those within r of the segment's x span are measured)."""
    px, py, pz = s0[S_X], s0[S_Y], s0[S_Z]
    sx, sy, sz = s1[S_X] - px, s1[S_Y] - py, s1[S_Z] - pz
    len2 = sx * sx + sy * sy + sz * sz
    lo = np.searchsorted(landmarks[:, 0], min(px, s1[S_X]) - r)
    hi = np.searchsorted(landmarks[:, 0], max(px, s1[S_X]) + r, side="right")
    for i in range(lo, hi):
        rx, ry, rz = landmarks[i, 0] - px, landmarks[i, 1] - py, landmarks[i, 2] - pz
        t = 0.0 if len2 <= 0 else min(max((rx * sx + ry * sy + rz * sz) / len2, 0.0), 1.0)
        mx, my, mz = rx - t * sx, ry - t * sy, rz - t * sz
        if math.sqrt(mx * mx + my * my + mz * mz) <= r:
            return True
    return False


@njit(cache=True, inline="always")
def finish_line(ex: float, ey: float, cx: float, cy: float, ax: float, ay: float) -> float:
    """Navigator.finish_line of the estimate (ex, ey) on the leg (ax, ay) -> (cx, cy)."""
    return (ex - cx) * (cx - ax) + (ey - cy) * (cy - ay)


@njit(cache=True, inline="always")
def waypoint_altitude_ok(rules: Rules, dz: float) -> bool:
    """Navigator.waypoint_altitude_ok: a waypoint reached horizontally ``dz`` m off its altitude
    counts as reached (PX4Navigator: within NAV_FW_ALT_RAD)."""
    return not rules.circles_for_altitude or dz <= ALTITUDE_ACCEPTANCE_M


@njit(cache=True, inline="always")
def track_decision(rules: Rules, cmds: Commands, j: int, prev: np.ndarray, ex: float, ey: float,
                   ez: float, acc: float, crossed: bool) -> tuple[int, float]:  # fmt: skip
    """Navigator._check_waypoint of command ``j`` after a step to the estimate (ex, ey, ez),
    with the acceptance ``acc`` of the step's start: (EVENT_*, the figure its text gives)."""
    cx, cy, cz = cmds.x[j], cmds.y[j], cmds.z[j]
    ax, ay = prev[0], prev[1]
    dist = math.hypot(cx - ex, cy - ey)
    # PX4Navigator.point_leg_without_finish_line: the switch distance decides alone.
    point_leg = rules.switches_early and math.hypot(cx - ax, cy - ay) < 1e-3
    passed = crossed or (finish_line(ex, ey, cx, cy, ax, ay) >= 0 and not point_leg)
    if dist <= acc or passed:
        dz = abs(ez - cz)
        if rules.circles_for_altitude and dz > ALTITUDE_ACCEPTANCE_M:
            return EVENT_ALTITUDE, dz
        return (EVENT_WITHIN if dist <= acc else EVENT_PASSED), dist
    return EVENT_NONE, 0.0


@njit(cache=True, inline="always")
def altitude_loiter_decision(new: np.ndarray, rules: Rules, cmds: Commands, j: int, ex: float,
                             ey: float, ez: float, limit: float) -> int:  # fmt: skip
    """Navigator._tick_altitude_loiter after a step: the altitude in and (PX4Navigator.
    exit_heading_ok, Navigator.course_lined_up) the course on the next waypoint, or none to
    line up on: EVENT_ALTITUDE_REACHED, else EVENT_NONE."""
    cx, cy, cz = cmds.x[j], cmds.y[j], cmds.z[j]
    if not abs(ez - cz) <= ALTITUDE_ACCEPTANCE_M:
        return EVENT_NONE
    if not cmds.has_next[j]:
        return EVENT_ALTITUDE_REACHED
    radius, _ = loiter_radius(new, rules, limit)
    nxx, nxy = cmds.next_x[j], cmds.next_y[j]
    if math.hypot(nxx - cx, nxy - cy) <= EXIT_REACHABLE * radius:
        return EVENT_ALTITUDE_REACHED
    bearing = math.atan2(nxy - ey, nxx - ex)
    if abs(wrap(bearing - new[S_COURSE])) <= math.radians(EXIT_COURSE_DEG):
        return EVENT_ALTITUDE_REACHED
    return EVENT_NONE


@njit(cache=True, inline="always")
def keep_step(state: np.ndarray, new: np.ndarray, min_dist: float, alt_error: float,
              settled: float, ux: float, uy: float, w1: float, w2: float, distance: float,
              row: np.ndarray, airspeed: float, seq: int) -> None:  # fmt: skip
    """The step to ``new`` kept: the state moves on, and its sample (Navigator.record: t, x, y,
    z, course, bank, climb, EAS, seq, heading, TAS, ground speed) is written into ``row``."""
    for i in range(AIRCRAFT_SIZE):
        state[i] = new[i]
    state[S_MIN_DIST], state[S_ALT_ERROR], state[S_SETTLED] = min_dist, alt_error, settled
    state[S_UX], state[S_UY], state[S_DISTANCE] = ux, uy, distance
    state[S_W1], state[S_W2] = w1, w2
    row[0], row[1], row[2], row[3] = state[S_T], state[S_X], state[S_Y], state[S_Z]
    row[4], row[5], row[6] = state[S_COURSE], state[S_BANK], state[S_CLIMB]
    row[7] = airspeed
    row[8], row[9], row[10], row[11] = seq, state[S_HEADING], state[S_TAS], state[S_GS]


@njit(cache=True, inline="always")
def record_event(events: np.ndarray, i: int, t: float, sample: int, seq: int, kind: int,
                 value: float) -> None:  # fmt: skip
    """Decision ``i``: at time ``t`` and sample row ``sample``, item ``seq``, EVENT_* ``kind``."""
    e = events[i]
    e[E_T], e[E_SAMPLE], e[E_SEQ], e[E_KIND], e[E_VALUE] = t, sample, seq, kind, value


@njit(cache=True, inline="always")
def advance(state: np.ndarray, cmds: Commands, j: int, prev: np.ndarray, ex: float, ey: float,
            ez: float) -> int:  # fmt: skip
    """Navigator.reached and advance onto the plain waypoint after ``j``: the next leg starts
    at the waypoint reached, or at the estimate when it is already past the new leg's finish
    line (ArduPlane set_next_WP); returns the new active command."""
    prev[0], prev[1], prev[2] = cmds.x[j], cmds.y[j], cmds.z[j]
    j += 1
    state[S_MIN_DIST] = math.inf
    nx, ny = cmds.x[j], cmds.y[j]
    if (ex - nx) * (nx - prev[0]) + (ey - ny) * (ny - prev[1]) > 0:
        prev[0], prev[1], prev[2] = ex, ey, ez
    return j
