"""The compiled flight (numba): the plain steps of mode AUTO, those where nothing happens but the
flight itself, and the waypoints of a mission, flown in one call until the next event.

The Python navigator (sim/navigators/) stays the reference and the test oracle
(``guidance.fly(..., compiled=False)``); this kernel flies, with the same formulas in the same
order, what makes most of a flight:

* tracking a waypoint (``Navigator.tick``: the acceptance radius of the autopilot, the glide
  slope, L1 on the line, the coarse step of a settled leg, the step stopped on the finish line,
  the aircraft step through the wind, rolling into its turns);
* PX4 circling a waypoint for its altitude (``Navigator._tick_altitude_loiter``: PX4's
  NAV_LOITER_RAD circle, climbing at its rate, until the altitude is in and the course is on the
  next waypoint);
* the decisions between plain waypoints (``Navigator._check_waypoint``, ``reached`` and
  ``advance``): a NAV_WAYPOINT reached within its acceptance radius or past its finish line,
  PX4 turning to circle one it reaches off its altitude and leaving that circle, and the next
  leg's start (ArduPlane's set_next_WP), when the item after it is a plain waypoint too. The
  events are handed back with the texts the Python navigator gives them.

A step is the kernel's when it passes within the capture radius of no unused landmark (the INS
then only counts the metres), needs no new batch of gust draws and, when something is reached,
reaches a plain waypoint followed by one. The kernel stops BEFORE the first step that is not
its own, without keeping it, and the Python navigator flies that step: every correction, every
draw of the seeded generators, every loiter item, DO item, landing and mission end stays in
Python, in the same order, so the seeded reports do not change. Only the rounding of a
reassociated sum may differ (tests/test_flight_kernel.py flies both).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from gcs_planner.aircraft.profile import G
from sim import atmosphere
from sim.aircraft import (
    ROLL_ONE_ARC_DEG_S,
    ROLL_RATE_DEG_S,
    ROLL_SETTLED_DEG,
    ROLL_SUBSTEP_S,
    ROLL_TAU_S,
    AircraftState,
)
from sim.navigators.base import ALTITUDE_TIME_CONSTANT_S, COARSE_STEPS, L1_DAMPING, L1_PERIOD_S
from sim.navigators.px4 import ALTITUDE_ACCEPTANCE_M, EXIT_COURSE_DEG, EXIT_REACHABLE

# Why the kernel stopped.
STOP_EVENT = 0  # the next step is not plain: the Python navigator flies it
STOP_FULL = 1  # the sample buffer is full: call again
STOP_TIME = 2  # the time limit is reached

MODE_TRACK = 0
MODE_ALTITUDE_LOITER = 1

FLAVOUR_ARDUPLANE = 0
FLAVOUR_PX4 = 1

# State vector (in and out).
S_X, S_Y, S_Z, S_COURSE, S_T, S_BANK, S_CLIMB, S_HEADING, S_TAS, S_GS = range(10)
S_MIN_DIST, S_ALT_ERROR, S_SETTLED, S_UX, S_UY, S_DISTANCE = range(10, 16)
STATE_SIZE = 16

# Constants of the flight (in).
(P_AIRSPEED, P_BANK, P_CLIMB, P_SINK, P_ALT_OFFSET, P_DT, P_TAU, P_SIGMA, P_WX, P_WY,
 P_TIME_LIMIT, P_FLAVOUR, P_WP_RADIUS, P_ACC_RADIUS, P_LOITER_RADIUS, P_NPFG_PERIOD,
 P_NPFG_DAMPING, P_NPFG_MULT, P_LOITER_BANK, P_INS, P_INS_SCALE, P_V0, P_V_AT, P_H0, P_H_AT,
 P_V_SIGN, P_H_DIR, P_CAPTURE, P_ROLL_TAU, P_ROLL_RATE, P_ROLL_SUBSTEP,
 P_ROLL_SETTLED, P_ROLL_ONE_ARC) = range(33)  # fmt: skip
PARAM_SIZE = 33

# The active command (in): its position, the leg's start, the next waypoint.
(C_X, C_Y, C_Z, C_PREV_X, C_PREV_Y, C_HAS_NEXT, C_NEXT_X, C_NEXT_Y, C_ACP, C_SEQ,
 C_MODE, C_PREV_Z) = range(12)  # fmt: skip
CMD_SIZE = 12

# The mission's commands (in), one row per navigator command: its position, ArduPlane's
# acceptance radius (param2), seq, the next waypoint it flies to, and whether it is a plain
# waypoint (a NAV_WAYPOINT with a position that the autopilot flies: the kernel may reach it
# and advance onto it; any other item is reached, skipped or flown by the Python navigator).
(T_X, T_Y, T_Z, T_ACP, T_SEQ, T_HAS_NEXT, T_NEXT_X, T_NEXT_Y, T_PLAIN) = range(9)  # fmt: skip
TABLE_SIZE = 9

# The decisions the kernel made (out), one row each: when, the sample row, the item's seq,
# what, and the figure the navigator's event text gives.
E_T, E_SAMPLE, E_SEQ, E_KIND, E_VALUE = range(5)
EVENT_SIZE = 5
EVENT_NONE = -1
EVENT_WITHIN = 0  # reached within the acceptance radius (value: the distance)
EVENT_PASSED = 1  # reached past the finish line (value: the distance)
EVENT_ALTITUDE = 2  # PX4 at the waypoint off its altitude, circling it (value: how far off)
EVENT_ALTITUDE_REACHED = 3  # PX4 leaves the altitude loiter of a waypoint

SAMPLE_SIZE = 12
_SIGMA11 = atmosphere._SIGMA11
_T11 = atmosphere._T11


@njit(cache=True)
def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


@njit(cache=True)
def _eas2tas(altitude_m: float) -> float:
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
def _max_lateral(bank_deg: float) -> float:
    return G * math.tan(math.radians(bank_deg))


@njit(cache=True)
def _acceptance(s: np.ndarray, p: np.ndarray, c: np.ndarray, e2t: float) -> float:
    """ArduPlaneNavigator.acceptance / PX4Navigator.acceptance (``e2t`` at the state's
    altitude)."""
    vg = max(s[S_GS], 1e-3)
    if p[P_FLAVOUR] == FLAVOUR_PX4:
        time_const = p[P_NPFG_PERIOD] * p[P_NPFG_DAMPING]
        bound = vg * time_const if vg > 1.0 else 0.5 * time_const * (vg * vg + 1.0)
        return max(p[P_ACC_RADIUS], min(500.0, bound * p[P_NPFG_MULT]))
    if c[C_ACP] > 0:
        return c[C_ACP]
    l1 = L1_DAMPING * L1_PERIOD_S * vg / math.pi
    turn = 90.0
    if c[C_HAS_NEXT] > 0:
        a1 = math.atan2(c[C_Y] - c[C_PREV_Y], c[C_X] - c[C_PREV_X])
        a2 = math.atan2(c[C_NEXT_Y] - c[C_Y], c[C_NEXT_X] - c[C_X])
        turn = min(abs(math.degrees(_wrap(a2 - a1))), 90.0)
    return min(p[P_WP_RADIUS] * e2t * e2t, l1) * turn / 90.0


@njit(cache=True)
def _arc(s: np.ndarray, p: np.ndarray, lateral: float, climb: float, dt: float, wx: float,
         wy: float, e2t: float, limit: float, out: np.ndarray) -> None:  # fmt: skip
    """sim/aircraft.py arc_step, for an aircraft with a turn limit (``limit``: its largest
    lateral acceleration, _max_lateral of its roll limit); writes the new state's first ten
    fields into ``out``, which may be ``s`` (each field is read before it is written)."""
    v = p[P_AIRSPEED] * e2t
    vz = min(max(climb, -p[P_SINK]), p[P_CLIMB])
    vh = math.sqrt(max(v * v - vz * vz, 0.0))
    psi0 = s[S_HEADING]
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
    out[S_Z] = s[S_Z] + vz * dt
    out[S_COURSE] = math.atan2(gy, gx)
    out[S_T] = s[S_T] + dt
    out[S_BANK] = -math.degrees(math.atan(a / G))
    out[S_CLIMB] = vz
    out[S_HEADING] = _wrap(psi1)
    out[S_TAS] = v
    out[S_GS] = math.hypot(gx, gy)


@njit(cache=True)
def _step(s: np.ndarray, p: np.ndarray, lateral: float, climb: float, dt: float, wx: float,
          wy: float, e2t: float, limit: float, out: np.ndarray) -> None:  # fmt: skip
    """sim/aircraft.py step (the bank rolling towards the one asked, in substeps), for an
    aircraft with a turn limit; writes the new state's first ten fields into ``out``."""
    bank_limit = p[P_BANK]
    asked = min(max(-math.degrees(math.atan(lateral / G)), -bank_limit), bank_limit)
    n = max(1, math.ceil(dt / p[P_ROLL_SUBSTEP] - 1e-9))
    h = dt / n
    keep = 1.0 - math.exp(-h / p[P_ROLL_TAU])
    most = p[P_ROLL_RATE] * h
    bank = s[S_BANK]
    gap = bank - asked
    if (p[P_ROLL_SETTLED] < abs(gap) <= p[P_ROLL_RATE] * p[P_ROLL_TAU]
            and abs(gap) * dt <= p[P_ROLL_ONE_ARC]):  # fmt: skip
        decay = math.exp(-dt / p[P_ROLL_TAU])
        mean = asked + gap * p[P_ROLL_TAU] * (1.0 - decay) / dt
        _arc(s, p, -G * math.tan(math.radians(mean)), climb, dt, wx, wy, e2t, limit, out)
        out[S_BANK] = asked + gap * decay
        return
    src = s
    for i in range(n):
        if abs(asked - bank) <= p[P_ROLL_SETTLED]:
            _arc(src, p, lateral, climb, dt - i * h, wx, wy, e2t, limit, out)
            return
        bank += min(max((asked - bank) * keep, -most), most)
        _arc(src, p, -G * math.tan(math.radians(bank)), climb, h, wx, wy, e2t, limit, out)
        src = out


@njit(cache=True)
def _offset(
    p: np.ndarray, distance: float, cos_h: float, sin_h: float
) -> tuple[float, float, float]:
    """InsEstimate.offset at ``distance`` flown (0 without an INS); ``cos_h``, ``sin_h`` of the
    error's direction."""
    if p[P_INS] <= 0:
        return 0.0, 0.0, 0.0
    v = p[P_V0] + (distance - p[P_V_AT])
    h = p[P_H0] + (distance - p[P_H_AT])
    dh = h * p[P_INS_SCALE]
    return dh * cos_h, dh * sin_h, p[P_V_SIGN] * v * p[P_INS_SCALE]


@njit(cache=True)
def _near_landmark(s0: np.ndarray, s1: np.ndarray, landmarks: np.ndarray, r: float) -> bool:
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


@njit(cache=True)
def _load_command(table: np.ndarray, j: int, prev: np.ndarray, mode: int, c: np.ndarray) -> None:
    """The active command vector ``c`` of command ``j`` of ``table`` (see _command_table)."""
    c[C_X], c[C_Y], c[C_Z] = table[j, T_X], table[j, T_Y], table[j, T_Z]
    c[C_PREV_X], c[C_PREV_Y], c[C_PREV_Z] = prev[0], prev[1], prev[2]
    c[C_HAS_NEXT], c[C_NEXT_X], c[C_NEXT_Y] = (
        table[j, T_HAS_NEXT],
        table[j, T_NEXT_X],
        table[j, T_NEXT_Y],
    )
    c[C_ACP], c[C_SEQ], c[C_MODE] = table[j, T_ACP], table[j, T_SEQ], mode


@njit(cache=True)
def fly_plain(
    state: np.ndarray,
    p: np.ndarray,
    table: np.ndarray,
    cmd: int,
    prev: np.ndarray,
    mode: int,
    landmarks: np.ndarray,
    normals: np.ndarray,
    k: int,
    samples: np.ndarray,
    events: np.ndarray,
) -> tuple[int, int, int, int, int, int]:
    """Fly the steps of command ``cmd`` of ``table`` and of the plain waypoints after it (module
    docstring) from ``state`` (updated in place) and the leg's start ``prev`` (updated when a
    waypoint is reached), in ``mode``, writing one row per step into ``samples`` and one per
    decision into ``events`` (time, sample row, seq, EVENT_*, the distance or altitude error
    its text gives); (steps, next gust draw index, why it stopped: STOP_EVENT, STOP_FULL or
    STOP_TIME, the active command, its mode, events)."""
    new = np.empty(STATE_SIZE)
    c = np.empty(CMD_SIZE)
    _load_command(table, cmd, prev, mode, c)
    dt0 = p[P_DT]
    coarse = dt0 * COARSE_STEPS
    px4 = p[P_FLAVOUR] == FLAVOUR_PX4
    gusty = p[P_SIGMA] > 0
    n = 0
    ne = 0
    e2t_z, e2t = math.nan, 1.0
    # Constant over the call: the roll limit's lateral acceleration, the error's direction.
    max_lat = _max_lateral(p[P_BANK])
    cos_h, sin_h = math.cos(p[P_H_DIR]), math.sin(p[P_H_DIR])
    # The estimate's offset at the distance flown (the end of a kept step is the next start).
    off_d = math.nan
    ox, oy, oz = 0.0, 0.0, 0.0
    while True:
        if n >= samples.shape[0] or ne >= events.shape[0]:
            return n, k, STOP_FULL, cmd, mode, ne
        if state[S_T] >= p[P_TIME_LIMIT]:
            return n, k, STOP_TIME, cmd, mode, ne
        if gusty and k + 2 > normals.shape[0]:
            return n, k, STOP_EVENT, cmd, mode, ne  # the Python wind field draws the next batch
        cx, cy, cz = c[C_X], c[C_Y], c[C_Z]
        ax, ay = c[C_PREV_X], c[C_PREV_Y]
        # Navigator.advance flies on to the next command only when it is a plain waypoint;
        # this command's decisions are the kernel's only when it is one itself.
        decides = table[cmd, T_PLAIN] > 0
        advances = decides and cmd + 1 < table.shape[0] and table[cmd + 1, T_PLAIN] > 0
        if state[S_DISTANCE] != off_d:
            off_d = state[S_DISTANCE]
            ox, oy, oz = _offset(p, off_d, cos_h, sin_h)
        ex, ey, ez = state[S_X] + ox, state[S_Y] + oy, state[S_Z] + oz
        vg = max(state[S_GS], 1e-3)
        l1 = L1_DAMPING * L1_PERIOD_S * vg / math.pi
        kk = 4.0 * L1_DAMPING * L1_DAMPING
        min_dist, alt_error, settled = state[S_MIN_DIST], state[S_ALT_ERROR], state[S_SETTLED]
        dt = dt0
        acc = 0.0
        # EAS2TAS at the state's altitude (one pow saved while the altitude holds).
        if state[S_Z] != e2t_z:
            e2t_z = state[S_Z]
            e2t = _eas2tas(e2t_z + p[P_ALT_OFFSET])
        if mode == MODE_TRACK:
            dist = math.hypot(cx - ex, cy - ey)
            acc = _acceptance(state, p, c, e2t)
            if dist <= acc and (not px4 or abs(ez - cz) <= ALTITUDE_ACCEPTANCE_M):
                # Navigator.tick: already there, reached at once without a step.
                if not advances:
                    return n, k, STOP_EVENT, cmd, mode, ne
                _event(events, ne, state[S_T], n - 1, c[C_SEQ], EVENT_WITHIN, dist)
                ne += 1
                cmd = _advance(state, table, cmd, prev, c, ex, ey, ez)
                continue
            # Navigator.glide from the leg's start.
            az = c[C_PREV_Z]
            end_dist = max(acc, abs(p[P_LOITER_RADIUS])) if px4 else 0.0
            total = math.hypot(cx - ax, cy - ay)
            span = total - end_dist
            if span <= 1e-6:
                climb = (cz - ez) / max(ALTITUDE_TIME_CONSTANT_S * 0.2, dt0)
            else:
                min_dist = min(min_dist, dist, total)
                progress = min(max((total - min_dist) / span, 0.0), 1.0)
                target = az + (cz - az) * progress
                alt_error = target - ez
                slope = (cz - az) / span
                # Navigator.glide: no feed-forward before the ramp starts
                ff = vg * slope if 0.0 < progress < 1.0 else 0.0
                climb = ff + (target - ez) / max(ALTITUDE_TIME_CONSTANT_S * 0.2, dt0)
            # Navigator.l1_line on prev -> c.
            abx, aby = cx - ax, cy - ay
            nrm = math.hypot(abx, aby)
            if nrm < 1e-6:
                abx, aby = cx - ex, cy - ey
                nrm = math.hypot(abx, aby) or 1.0
            ux, uy = abx / nrm, aby / nrm
            rx, ry = ex - ax, ey - ay
            ccx, ccy = math.cos(state[S_COURSE]), math.sin(state[S_COURSE])
            dist_a = math.hypot(rx, ry)
            along = rx * ux + ry * uy
            settled = 0.0
            if dist_a > l1 and along < -0.7071 * dist_a:
                nu = _wrap(math.atan2(-ry, -rx) - state[S_COURSE])
            else:
                xtrack = ux * ry - uy * rx
                nu1 = math.asin(max(-0.7071, min(0.7071, xtrack / l1)))
                eta = math.atan2(ux * ccy - uy * ccx, ux * ccx + uy * ccy)
                nu = -(nu1 + eta)
                settled = 1.0 if abs(xtrack) < 0.5 and abs(eta) < 0.005 else 0.0
            nu = max(-math.pi / 2, min(math.pi / 2, nu))
            lateral = kk * vg * vg / l1 * math.sin(nu)
            if (
                settled > 0
                and not gusty
                and abs(alt_error) < 0.5
                and dist > 3.0 * vg * coarse
                and -p[P_SINK] < climb < p[P_CLIMB]
            ):
                dt = coarse
                # Navigator.tick: the altitude error flown out over the coarse step.
                climb += alt_error * (1.0 / coarse - 1.0 / max(ALTITUDE_TIME_CONSTANT_S * 0.2, dt0))
        else:
            # PX4Navigator circling waypoint c on NAV_LOITER_RAD for its altitude.
            lr = p[P_LOITER_RADIUS]
            radius = max(abs(lr), state[S_TAS] * state[S_TAS] / max_lat)
            direction = -1 if lr >= 0 else 1
            rx, ry = ex - cx, ey - cy
            r = math.hypot(rx, ry)
            theta = math.atan2(ry, rx)
            intercept = math.atan((r - radius) / (0.5 * l1))
            want = theta + direction * (math.pi / 2 + intercept)
            err = _wrap(want - state[S_COURSE])
            ff = direction * vg * vg / radius if radius > 0 and abs(r - radius) < l1 else 0.0
            lateral = ff + kk * vg * vg / l1 * math.sin(max(-math.pi / 2, min(math.pi / 2, err)))
            climb = (cz - ez) / max(ALTITUDE_TIME_CONSTANT_S * 0.2, dt0)
        # WindField.step
        gx_u, gy_u = state[S_UX], state[S_UY]
        kn = k
        if gusty:
            a = math.exp(-dt / p[P_TAU])
            b = p[P_SIGMA] * math.sqrt(1.0 - a * a)
            gx_u = gx_u * a + b * normals[kn]
            gy_u = gy_u * a + b * normals[kn + 1]
            kn += 2
        wx, wy = p[P_WX] + gx_u, p[P_WY] + gy_u
        _step(state, p, lateral, climb, dt, wx, wy, e2t, max_lat, new)
        crossed = False
        if mode == MODE_TRACK:
            # Navigator.finish_line before and after, on the estimate's offset of the start.
            fx0 = (ex - cx) * (cx - ax) + (ey - cy) * (cy - ay)
            nx, ny = new[S_X] + (ex - state[S_X]), new[S_Y] + (ey - state[S_Y])
            fx1 = (nx - cx) * (cx - ax) + (ny - cy) * (cy - ay)
            if fx0 < 0 <= fx1:
                if not decides:
                    return n, k, STOP_EVENT, cmd, mode, ne
                # Navigator.tick stops the step on the finish line.
                crossed = True
                _step(state, p, lateral, climb, dt * fx0 / (fx0 - fx1), wx, wy, e2t, max_lat, new)
        if p[P_INS] > 0 and _near_landmark(state, new, landmarks, p[P_CAPTURE]):
            return n, k, STOP_EVENT, cmd, mode, ne
        sx, sy, sz = new[S_X] - state[S_X], new[S_Y] - state[S_Y], new[S_Z] - state[S_Z]
        distance = state[S_DISTANCE] + math.sqrt(sx * sx + sy * sy + sz * sz)
        off_d = distance
        ox, oy, oz = _offset(p, off_d, cos_h, sin_h)
        ex, ey, ez = new[S_X] + ox, new[S_Y] + oy, new[S_Z] + oz
        event = EVENT_NONE
        value = 0.0
        if mode == MODE_TRACK:
            # Navigator._check_waypoint with the acceptance of the step's start.
            dist = math.hypot(cx - ex, cy - ey)
            point_leg = px4 and math.hypot(cx - ax, cy - ay) < 1e-3
            passed = crossed or (
                (ex - cx) * (cx - ax) + (ey - cy) * (cy - ay) >= 0 and not point_leg
            )
            if dist <= acc or passed:
                dz = abs(ez - cz)
                if px4 and dz > ALTITUDE_ACCEPTANCE_M:
                    event, value = EVENT_ALTITUDE, dz
                else:
                    event, value = (EVENT_WITHIN if dist <= acc else EVENT_PASSED), dist
        elif abs(ez - cz) <= ALTITUDE_ACCEPTANCE_M:
            # PX4Navigator.exit_heading_ok after the step (Navigator.course_lined_up).
            if c[C_HAS_NEXT] <= 0:
                event = EVENT_ALTITUDE_REACHED
            else:
                radius = max(abs(p[P_LOITER_RADIUS]), new[S_TAS] * new[S_TAS] / max_lat)
                nxx, nxy = c[C_NEXT_X], c[C_NEXT_Y]
                if math.hypot(nxx - cx, nxy - cy) <= EXIT_REACHABLE * radius:
                    event = EVENT_ALTITUDE_REACHED
                else:
                    bearing = math.atan2(nxy - ey, nxx - ex)
                    if abs(_wrap(bearing - new[S_COURSE])) <= math.radians(EXIT_COURSE_DEG):
                        event = EVENT_ALTITUDE_REACHED
        if event != EVENT_NONE and not (advances or (event == EVENT_ALTITUDE and decides)):
            return n, k, STOP_EVENT, cmd, mode, ne
        # The step is kept.
        for j in range(10):
            state[j] = new[j]
        state[S_MIN_DIST], state[S_ALT_ERROR], state[S_SETTLED] = min_dist, alt_error, settled
        state[S_UX], state[S_UY], state[S_DISTANCE] = gx_u, gy_u, distance
        k = kn
        row = samples[n]
        row[0], row[1], row[2], row[3] = state[S_T], state[S_X], state[S_Y], state[S_Z]
        row[4], row[5], row[6] = state[S_COURSE], state[S_BANK], state[S_CLIMB]
        row[7] = p[P_AIRSPEED]
        row[8], row[9], row[10], row[11] = c[C_SEQ], state[S_HEADING], state[S_TAS], state[S_GS]
        n += 1
        if event == EVENT_ALTITUDE:
            # PX4: at the waypoint but off its altitude: circle it.
            _event(events, ne, state[S_T], n - 1, c[C_SEQ], event, value)
            ne += 1
            mode = MODE_ALTITUDE_LOITER
            c[C_MODE] = mode
        elif event != EVENT_NONE:
            _event(events, ne, state[S_T], n - 1, c[C_SEQ], event, value)
            ne += 1
            mode = MODE_TRACK
            cmd = _advance(state, table, cmd, prev, c, ex, ey, ez)


@njit(cache=True)
def _event(events: np.ndarray, i: int, t: float, sample: int, seq: float, kind: int,
           value: float) -> None:  # fmt: skip
    e = events[i]
    e[E_T], e[E_SAMPLE], e[E_SEQ], e[E_KIND], e[E_VALUE] = t, sample, seq, kind, value


@njit(cache=True)
def _advance(state: np.ndarray, table: np.ndarray, cmd: int, prev: np.ndarray, c: np.ndarray,
             ex: float, ey: float, ez: float) -> int:  # fmt: skip
    """Navigator.reached and advance onto the plain waypoint after ``cmd``: the next leg starts
    at the waypoint reached, or at the estimate when it is already past the new leg's finish
    line (ArduPlane set_next_WP); returns the new active command."""
    prev[0], prev[1], prev[2] = table[cmd, T_X], table[cmd, T_Y], table[cmd, T_Z]
    cmd += 1
    state[S_MIN_DIST] = math.inf
    nx, ny = table[cmd, T_X], table[cmd, T_Y]
    if (ex - nx) * (nx - prev[0]) + (ey - ny) * (ny - prev[1]) > 0:
        prev[0], prev[1], prev[2] = ex, ey, ez
    _load_command(table, cmd, prev, MODE_TRACK, c)
    return cmd


# The Python side ------------------------------------------------------------------------------
_BUFFER_STEPS = 4096


def _landmarks(ins: object, cache: dict) -> np.ndarray:
    """The V and H landmarks the INS has not used yet, (n, 3), cached per count of used ones."""
    used = ins._used  # type: ignore[attr-defined]
    key = len(used)
    if cache.get("key") != key:
        sc = ins.scenario  # type: ignore[attr-defined]
        idx = [li for cell in ins._grid.values() for li in cell if li not in used]  # type: ignore[attr-defined]
        cache["key"] = key
        xyz = np.asarray(sc.xyz[sorted(idx)], dtype=float).reshape(-1, 3)
        cache["xyz"] = np.ascontiguousarray(xyz[np.argsort(xyz[:, 0], kind="stable")])
    return cache["xyz"]


def _command_table(nav: object) -> np.ndarray:
    """The navigator's commands as the kernel reads them (T_* columns)."""
    from sim.navigators.base import NAV_WAYPOINT

    cmds = nav.cmds  # type: ignore[attr-defined]
    px4 = nav.flavour == "px4"  # type: ignore[attr-defined]
    table = np.zeros((len(cmds), TABLE_SIZE))
    for j, cmd in enumerate(cmds):
        table[j, T_SEQ] = cmd.seq
        if cmd.pos is None:
            continue
        table[j, T_X], table[j, T_Y], table[j, T_Z] = cmd.pos
        if not px4 and cmd.command == NAV_WAYPOINT:
            table[j, T_ACP] = float(int(cmd.params[1]) & 0xFF)
        # Navigator.next_target with command j active.
        after = nav._next_nav_index(j + 1)  # type: ignore[attr-defined]
        nxt = None if after is None else cmds[after].pos
        if nxt is not None:
            table[j, T_HAS_NEXT], table[j, T_NEXT_X], table[j, T_NEXT_Y] = 1.0, nxt[0], nxt[1]
        plain = cmd.command == NAV_WAYPOINT and nav.flies(cmd)  # type: ignore[attr-defined]
        table[j, T_PLAIN] = 1.0 if plain else 0.0
    return table


_EVENT_KINDS = {EVENT_WITHIN: "reached", EVENT_PASSED: "reached", EVENT_ALTITUDE: "altitude",
                EVENT_ALTITUDE_REACHED: "reached"}  # fmt: skip


def _event_text(kind: int, value: float) -> str:
    """The text Navigator._check_waypoint and _tick_altitude_loiter give the event."""
    if kind == EVENT_WITHIN:
        return f"within {value:.1f} m"
    if kind == EVENT_PASSED:
        return f"passed at {value:.1f} m"
    if kind == EVENT_ALTITUDE:
        return f"{value:.0f} m off its altitude: circling it"
    return "altitude reached circling it"


def fly_plain_steps(pilot: object, time_limit: float, cache: dict) -> None:
    """Fly the navigator ``pilot``'s plain steps in the kernel (module docstring), if its
    active command and phase are of the kinds the kernel flies; the navigator's state, its
    samples and events, the active command, the wind field's gusts and the INS's distance are
    updated as the Python steps would have. Returns before the first step the Python navigator
    must fly."""
    from sim.navigators.base import LOITERS, Event

    nav = pilot  # a sim.navigators.base.Navigator
    if nav.free_turn or nav.k < 0 or nav.k >= len(nav.cmds):  # type: ignore[attr-defined]
        return
    cmd = nav.cmds[nav.k]  # type: ignore[attr-defined]
    if cmd.command in LOITERS or cmd.pos is None:
        return
    px4 = nav.flavour == "px4"  # type: ignore[attr-defined]
    if nav.phase == "track":  # type: ignore[attr-defined]
        mode = MODE_TRACK
    elif nav.phase == "loiter" and px4:  # type: ignore[attr-defined]
        mode = MODE_ALTITUDE_LOITER
    else:
        return
    ins = nav.ins  # type: ignore[attr-defined]
    if ins is not None and (ins._passes or ins.lost):
        return
    wind = nav.wind  # type: ignore[attr-defined]
    s, env, ap = nav.s, nav.env, nav.ap  # type: ignore[attr-defined]
    table = cache.get("table")
    if table is None:
        table = cache["table"] = _command_table(nav)
    p = np.zeros(PARAM_SIZE)
    p[P_AIRSPEED], p[P_BANK], p[P_CLIMB], p[P_SINK] = (
        env.airspeed,
        env.bank_limit_deg,
        env.climb_rate,
        env.sink_rate,
    )
    p[P_ALT_OFFSET], p[P_DT], p[P_TIME_LIMIT] = nav.alt_offset, nav.dt, time_limit  # type: ignore[attr-defined]
    p[P_FLAVOUR] = FLAVOUR_PX4 if px4 else FLAVOUR_ARDUPLANE
    p[P_WP_RADIUS], p[P_ACC_RADIUS], p[P_LOITER_RADIUS] = (
        ap.wp_radius,
        ap.acceptance_radius,
        ap.loiter_radius,
    )
    p[P_NPFG_PERIOD], p[P_NPFG_DAMPING], p[P_NPFG_MULT] = (
        ap.npfg_period,
        ap.npfg_damping,
        ap.npfg_switch_multiplier,
    )
    p[P_LOITER_BANK] = ap.loiter_bank_limit
    p[P_ROLL_TAU], p[P_ROLL_RATE] = ROLL_TAU_S, ROLL_RATE_DEG_S
    p[P_ROLL_SUBSTEP], p[P_ROLL_SETTLED] = ROLL_SUBSTEP_S, ROLL_SETTLED_DEG
    p[P_ROLL_ONE_ARC] = ROLL_ONE_ARC_DEG_S
    normals = _EMPTY
    k = 0
    if wind is not None:
        p[P_TAU], p[P_SIGMA], p[P_WX], p[P_WY] = wind.tau, wind.sigma, wind.wx, wind.wy
        normals, k = wind._normals, wind._k
    landmarks = _EMPTY_XYZ
    if ins is not None:
        p[P_INS], p[P_INS_SCALE] = 1.0, ins.scale
        p[P_V0], p[P_V_AT], p[P_H0], p[P_H_AT] = ins.v0, ins.v_at, ins.h0, ins.h_at
        p[P_V_SIGN], p[P_H_DIR], p[P_CAPTURE] = ins.v_sign, ins.h_dir, ins.capture
        landmarks = _landmarks(ins, cache)
    state = np.array([
        s.x, s.y, s.z, s.course, s.t, s.bank_deg, s.climb_rate, s.heading, s.tas,
        s.ground_speed, nav.min_dist, nav.alt_error, 1.0 if nav.settled else 0.0,  # type: ignore[attr-defined]
        0.0 if wind is None else wind.ux, 0.0 if wind is None else wind.uy,
        0.0 if ins is None else ins.distance,
    ])  # fmt: skip
    prev = np.array(nav.prev, dtype=float)  # type: ignore[attr-defined]
    events = cache.get("events")
    if events is None:
        events = cache["events"] = np.empty((_EVENT_ROWS, EVENT_SIZE))
    k_cmd = nav.k  # type: ignore[attr-defined]
    total = 0
    decided = 0
    while True:
        nav.reserve(_BUFFER_STEPS)  # type: ignore[attr-defined]
        start = nav.n_samples  # type: ignore[attr-defined]
        rows = nav.track[start : start + _BUFFER_STEPS]  # type: ignore[attr-defined]
        n, k, why, k_cmd, mode, ne = fly_plain(
            state, p, table, k_cmd, prev, mode, landmarks, normals, k, rows, events
        )
        for e in events[:ne].tolist():
            kind = int(e[E_KIND])
            nav.events.append(  # type: ignore[attr-defined]
                Event(e[E_T], start + int(e[E_SAMPLE]), int(e[E_SEQ]), _EVENT_KINDS[kind],
                      _event_text(kind, e[E_VALUE]))
            )  # fmt: skip
        nav.n_samples += n  # type: ignore[attr-defined]
        total += n
        decided += ne
        if why != STOP_FULL:
            break
    if total == 0 and decided == 0:
        return
    x, y, z, course, t, bank, climb, heading, tas, gs = state[:10].tolist()
    nav.s = AircraftState(x, y, z, course, t, bank, climb, heading, tas, gs)  # type: ignore[attr-defined]
    nav.min_dist, nav.alt_error = float(state[S_MIN_DIST]), float(state[S_ALT_ERROR])  # type: ignore[attr-defined]
    nav.settled = bool(state[S_SETTLED] > 0)  # type: ignore[attr-defined]
    if wind is not None:
        wind.ux, wind.uy, wind._k = float(state[S_UX]), float(state[S_UY]), int(k)
    if ins is not None:
        ins.distance = float(state[S_DISTANCE])
    if decided:
        if k_cmd != nav.k:  # type: ignore[attr-defined]
            # Navigator.advance's resets of the loiter state.
            nav.k = k_cmd  # type: ignore[attr-defined]
            nav.loiter_sum, nav.loiter_started, nav.hold_alt = 0.0, False, None  # type: ignore[attr-defined]
            x0, y0, z0 = prev.tolist()
            nav.prev = (x0, y0, z0)  # type: ignore[attr-defined]
        nav.phase = "track" if mode == MODE_TRACK else "loiter"  # type: ignore[attr-defined]
    nav._estimate()  # type: ignore[attr-defined]


_EVENT_ROWS = 256


_EMPTY = np.empty(0)
_EMPTY_XYZ = np.empty((0, 3))


@njit(cache=True)
def _segment_miss(points: np.ndarray, i: int, point: np.ndarray) -> tuple[float, float]:
    """(3D miss, fraction along) of segment i of ``points`` at its closest to ``point``."""
    dx = points[i + 1, 0] - points[i, 0]
    dy = points[i + 1, 1] - points[i, 1]
    dz = points[i + 1, 2] - points[i, 2]
    rx, ry, rz = point[0] - points[i, 0], point[1] - points[i, 1], point[2] - points[i, 2]
    len2 = dx * dx + dy * dy + dz * dz
    t = (rx * dx + ry * dy + rz * dz) / len2 if len2 > 0 else 0.0
    t = min(max(t, 0.0), 1.0)
    mx, my, mz = rx - t * dx, ry - t * dy, rz - t * dz
    return math.sqrt(mx * mx + my * my + mz * mz), t


TRACK_BLOCK = 64  # segments per bounding box of track_blocks


@njit(cache=True)
def track_blocks(points: np.ndarray) -> np.ndarray:
    """The bounding box (x, y, z low, then high) of each TRACK_BLOCK segments of the track
    ``points``: closest_approach skips the blocks too far to matter."""
    m = points.shape[0] - 1
    nb = (m + TRACK_BLOCK - 1) // TRACK_BLOCK
    out = np.empty((nb, 6))
    for b in range(nb):
        lo = b * TRACK_BLOCK
        hi = min(lo + TRACK_BLOCK, m)
        for a in range(3):
            v0 = points[lo, a]
            v1 = v0
            for i in range(lo + 1, hi + 1):
                v = points[i, a]
                v0 = min(v0, v)
                v1 = max(v1, v)
            out[b, a], out[b, a + 3] = v0, v1
    return out


@njit(cache=True)
def _block_distance(blocks: np.ndarray, b: int, point: np.ndarray) -> float:
    d2 = 0.0
    for a in range(3):
        g = max(blocks[b, a] - point[a], 0.0, point[a] - blocks[b, a + 3])
        d2 += g * g
    return math.sqrt(d2)


@njit(cache=True)
def closest_approach(
    points: np.ndarray,
    cumulative: np.ndarray,
    point: np.ndarray,
    radius: float,
    blocks: np.ndarray,
) -> tuple[float, float]:
    """sim/replay.py closest_approach over the track ``points`` (m >= 2, 3) with its
    ``cumulative`` length and ``track_blocks``: (distance flown, 3D miss) at the closest
    approach of the first pass within ``radius`` of ``point``, else at the closest approach
    overall (the first segment of the least miss, as numpy's argmin). One pass, stopping at
    the end of the first pass; a block of segments whose bounding box is farther than the
    radius and than the least miss so far (by more than rounding) is skipped: none of its
    segments could be in a pass or a new least."""
    m = points.shape[0] - 1
    best_j, best_miss, best_t = 0, math.inf, 0.0
    for b in range(blocks.shape[0]):
        gap = _block_distance(blocks, b, point) - 1e-6
        if gap > radius and gap > best_miss:
            continue
        for i in range(b * TRACK_BLOCK, min((b + 1) * TRACK_BLOCK, m)):
            miss, t = _segment_miss(points, i, point)
            if miss <= radius:
                # The first pass: its least miss, up to the first segment outside the radius.
                j, jm, jt = i, miss, t
                i += 1
                while i < m:
                    miss, t = _segment_miss(points, i, point)
                    if miss > radius:
                        break
                    if miss < jm:
                        j, jm, jt = i, miss, t
                    i += 1
                return cumulative[j] + jt * (cumulative[j + 1] - cumulative[j]), jm
            if miss < best_miss:
                best_j, best_miss, best_t = i, miss, t
    j = best_j
    return cumulative[j] + best_t * (cumulative[j + 1] - cumulative[j]), best_miss
