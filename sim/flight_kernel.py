"""The compiled flight (numba): the plain steps of mode AUTO, those where nothing happens but the
flight itself, flown in one call until the next event.

The Python navigator (sim/navigators/) stays the reference and the test oracle
(``guidance.fly(..., compiled=False)``); this kernel flies, with the same formulas in the same
order, the two kinds of step that make most of a flight:

* tracking a waypoint (``Navigator.tick``: the acceptance radius of the autopilot, the glide
  slope, L1 on the line, the coarse step of a settled leg, the aircraft step through the wind);
* PX4 circling a waypoint for its altitude (``Navigator._tick_altitude_loiter``: PX4's
  NAV_LOITER_RAD circle, climbing at its rate, until the altitude is in and the course is on the
  next waypoint).

A step is plain when it reaches nothing (not the waypoint's acceptance circle nor its finish
line, not the altitude loiter's exit), passes within the capture radius of no unused landmark
(the INS then only counts the metres) and needs no new batch of gust draws. The kernel stops
BEFORE the first step that is not plain, without keeping it, and the Python navigator flies
that step: every decision, every draw of the seeded generators and every correction stays in
Python, in the same order, so the seeded reports do not change. Only the rounding of a
reassociated sum may differ (tests/test_flight_kernel.py flies both).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from gcs_planner.vehicle import G
from sim import atmosphere
from sim.aircraft import AircraftState
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
 P_V_SIGN, P_H_DIR, P_CAPTURE) = range(28)  # fmt: skip
PARAM_SIZE = 28

# The active command (in): its position, the leg's start, the next waypoint.
(C_X, C_Y, C_Z, C_PREV_X, C_PREV_Y, C_HAS_NEXT, C_NEXT_X, C_NEXT_Y, C_ACP, C_SEQ,
 C_MODE, C_PREV_Z) = range(12)  # fmt: skip
CMD_SIZE = 12

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
def _acceptance(s: np.ndarray, p: np.ndarray, c: np.ndarray) -> float:
    """ArduPlaneNavigator.acceptance / PX4Navigator.acceptance."""
    vg = max(s[S_GS], 1e-3)
    if p[P_FLAVOUR] == FLAVOUR_PX4:
        time_const = p[P_NPFG_PERIOD] * p[P_NPFG_DAMPING]
        bound = vg * time_const if vg > 1.0 else 0.5 * time_const * (vg * vg + 1.0)
        return max(p[P_ACC_RADIUS], min(500.0, bound * p[P_NPFG_MULT]))
    if c[C_ACP] > 0:
        return c[C_ACP]
    e2t = _eas2tas(s[S_Z] + p[P_ALT_OFFSET])
    l1 = L1_DAMPING * L1_PERIOD_S * vg / math.pi
    turn = 90.0
    if c[C_HAS_NEXT] > 0:
        a1 = math.atan2(c[C_Y] - c[C_PREV_Y], c[C_X] - c[C_PREV_X])
        a2 = math.atan2(c[C_NEXT_Y] - c[C_Y], c[C_NEXT_X] - c[C_X])
        turn = min(abs(math.degrees(_wrap(a2 - a1))), 90.0)
    return min(p[P_WP_RADIUS] * e2t * e2t, l1) * turn / 90.0


@njit(cache=True)
def _step(s: np.ndarray, p: np.ndarray, lateral: float, climb: float, dt: float, wx: float,
          wy: float, e2t: float, out: np.ndarray) -> None:  # fmt: skip
    """sim/aircraft.py step, for an aircraft with a turn limit; writes the new state's first
    ten fields into ``out``."""
    v = p[P_AIRSPEED] * e2t
    vz = min(max(climb, -p[P_SINK]), p[P_CLIMB])
    vh = math.sqrt(max(v * v - vz * vz, 0.0))
    psi0 = s[S_HEADING]
    limit = _max_lateral(p[P_BANK])
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
def _offset(p: np.ndarray, distance: float) -> tuple[float, float, float]:
    """InsEstimate.offset at ``distance`` flown (0 without an INS)."""
    if p[P_INS] <= 0:
        return 0.0, 0.0, 0.0
    v = p[P_V0] + (distance - p[P_V_AT])
    h = p[P_H0] + (distance - p[P_H_AT])
    dh = h * p[P_INS_SCALE]
    return dh * math.cos(p[P_H_DIR]), dh * math.sin(p[P_H_DIR]), p[P_V_SIGN] * v * p[P_INS_SCALE]


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
def fly_plain(
    state: np.ndarray,
    p: np.ndarray,
    c: np.ndarray,
    landmarks: np.ndarray,
    normals: np.ndarray,
    k: int,
    samples: np.ndarray,
) -> tuple[int, int, int]:
    """Fly plain steps of the active command (module docstring) from ``state`` (updated in
    place), writing one row per step into ``samples``; (steps, next gust draw index, why it
    stopped: STOP_EVENT, STOP_FULL or STOP_TIME)."""
    new = np.empty(STATE_SIZE)
    dt0 = p[P_DT]
    coarse = dt0 * COARSE_STEPS
    cx, cy, cz = c[C_X], c[C_Y], c[C_Z]
    ax, ay = c[C_PREV_X], c[C_PREV_Y]
    mode = int(c[C_MODE])
    px4 = p[P_FLAVOUR] == FLAVOUR_PX4
    gusty = p[P_SIGMA] > 0
    n = 0
    while True:
        if n >= samples.shape[0]:
            return n, k, STOP_FULL
        if state[S_T] >= p[P_TIME_LIMIT]:
            return n, k, STOP_TIME
        if gusty and k + 2 > normals.shape[0]:
            return n, k, STOP_EVENT  # the Python wind field draws the next batch
        ox, oy, oz = _offset(p, state[S_DISTANCE])
        ex, ey, ez = state[S_X] + ox, state[S_Y] + oy, state[S_Z] + oz
        vg = max(state[S_GS], 1e-3)
        l1 = L1_DAMPING * L1_PERIOD_S * vg / math.pi
        kk = 4.0 * L1_DAMPING * L1_DAMPING
        min_dist, alt_error, settled = state[S_MIN_DIST], state[S_ALT_ERROR], state[S_SETTLED]
        dt = dt0
        acc = 0.0
        if mode == MODE_TRACK:
            dist = math.hypot(cx - ex, cy - ey)
            acc = _acceptance(state, p, c)
            if dist <= acc and (not px4 or abs(ez - cz) <= ALTITUDE_ACCEPTANCE_M):
                return n, k, STOP_EVENT
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
                ff = vg * slope if progress < 1.0 else 0.0
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
        else:
            # PX4Navigator circling waypoint c on NAV_LOITER_RAD for its altitude.
            lr = p[P_LOITER_RADIUS]
            max_lat = _max_lateral(p[P_BANK])
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
        e2t = _eas2tas(state[S_Z] + p[P_ALT_OFFSET])
        _step(state, p, lateral, climb, dt, wx, wy, e2t, new)
        if mode == MODE_TRACK:
            # Navigator.finish_line before and after, on the estimate's offset of the start.
            fx0 = (ex - cx) * (cx - ax) + (ey - cy) * (cy - ay)
            nx, ny = new[S_X] + (ex - state[S_X]), new[S_Y] + (ey - state[S_Y])
            fx1 = (nx - cx) * (cx - ax) + (ny - cy) * (cy - ay)
            if fx0 < 0 <= fx1:
                return n, k, STOP_EVENT
        if p[P_INS] > 0 and _near_landmark(state, new, landmarks, p[P_CAPTURE]):
            return n, k, STOP_EVENT
        sx, sy, sz = new[S_X] - state[S_X], new[S_Y] - state[S_Y], new[S_Z] - state[S_Z]
        distance = state[S_DISTANCE] + math.sqrt(sx * sx + sy * sy + sz * sz)
        ox, oy, oz = _offset(p, distance)
        ex, ey, ez = new[S_X] + ox, new[S_Y] + oy, new[S_Z] + oz
        if mode == MODE_TRACK:
            # Navigator._check_waypoint with the acceptance of the step's start.
            dist = math.hypot(cx - ex, cy - ey)
            point_leg = px4 and math.hypot(cx - ax, cy - ay) < 1e-3
            passed = (ex - cx) * (cx - ax) + (ey - cy) * (cy - ay) >= 0 and not point_leg
            if dist <= acc or passed:
                return n, k, STOP_EVENT
        else:
            if abs(ez - cz) <= ALTITUDE_ACCEPTANCE_M:
                # PX4Navigator.exit_heading_ok after the step (Navigator.course_lined_up).
                if c[C_HAS_NEXT] <= 0:
                    return n, k, STOP_EVENT
                radius = max(abs(p[P_LOITER_RADIUS]), new[S_TAS] * new[S_TAS] / max_lat)
                nxx, nxy = c[C_NEXT_X], c[C_NEXT_Y]
                if math.hypot(nxx - cx, nxy - cy) <= EXIT_REACHABLE * radius:
                    return n, k, STOP_EVENT
                bearing = math.atan2(nxy - ey, nxx - ex)
                if abs(_wrap(bearing - new[S_COURSE])) <= math.radians(EXIT_COURSE_DEG):
                    return n, k, STOP_EVENT
        # The step is plain: keep it.
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


def fly_plain_steps(pilot: object, time_limit: float, cache: dict) -> None:
    """Fly the navigator ``pilot``'s plain steps in the kernel (module docstring), if its
    active command and phase are of the kinds the kernel flies; the navigator's state, its
    samples, the wind field's gusts and the INS's distance are updated as the Python steps
    would have. Returns before the first step the Python navigator must fly."""
    from sim.navigators.base import LOITERS

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
    nxt = nav.next_target()  # type: ignore[attr-defined]
    prev = nav.prev  # type: ignore[attr-defined]
    acp = 0.0
    if not px4 and cmd.command == 16:
        acp = float(int(cmd.params[1]) & 0xFF)
    c = np.array([
        cmd.pos[0], cmd.pos[1], cmd.pos[2], prev[0], prev[1], 0.0 if nxt is None else 1.0,
        0.0 if nxt is None else nxt[0], 0.0 if nxt is None else nxt[1], acp, cmd.seq, mode,
        prev[2],
    ])  # fmt: skip
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
    total = 0
    while True:
        nav.reserve(_BUFFER_STEPS)  # type: ignore[attr-defined]
        start = nav.n_samples  # type: ignore[attr-defined]
        rows = nav.track[start : start + _BUFFER_STEPS]  # type: ignore[attr-defined]
        n, k, why = fly_plain(state, p, c, landmarks, normals, k, rows)
        nav.n_samples += n  # type: ignore[attr-defined]
        total += n
        if why != STOP_FULL:
            break
    if total == 0:
        return
    x, y, z, course, t, bank, climb, heading, tas, gs = (float(v) for v in state[:10])
    nav.s = AircraftState(x, y, z, course, t, bank, climb, heading, tas, gs)  # type: ignore[attr-defined]
    nav.min_dist, nav.alt_error = float(state[S_MIN_DIST]), float(state[S_ALT_ERROR])  # type: ignore[attr-defined]
    nav.settled = bool(state[S_SETTLED] > 0)  # type: ignore[attr-defined]
    if wind is not None:
        wind.ux, wind.uy, wind._k = float(state[S_UX]), float(state[S_UY]), int(k)
    if ins is not None:
        ins.distance = float(state[S_DISTANCE])
    nav._estimate()  # type: ignore[attr-defined]


_EMPTY = np.empty(0)
_EMPTY_XYZ = np.empty((0, 3))


@njit(cache=True)
def closest_approach(
    points: np.ndarray, cumulative: np.ndarray, point: np.ndarray, radius: float
) -> tuple[float, float]:
    """sim/replay.py closest_approach over the track ``points`` (m >= 2, 3) with its
    ``cumulative`` length: (distance flown, 3D miss) at the closest approach of the first pass
    within ``radius`` of ``point``, else at the closest approach overall."""
    m = points.shape[0] - 1
    miss = np.empty(m)
    ts = np.empty(m)
    for i in range(m):
        dx = points[i + 1, 0] - points[i, 0]
        dy = points[i + 1, 1] - points[i, 1]
        dz = points[i + 1, 2] - points[i, 2]
        rx, ry, rz = point[0] - points[i, 0], point[1] - points[i, 1], point[2] - points[i, 2]
        len2 = dx * dx + dy * dy + dz * dz
        t = (rx * dx + ry * dy + rz * dz) / len2 if len2 > 0 else 0.0
        t = min(max(t, 0.0), 1.0)
        mx, my, mz = rx - t * dx, ry - t * dy, rz - t * dz
        miss[i] = math.sqrt(mx * mx + my * my + mz * mz)
        ts[i] = t
    first = -1
    for i in range(m):
        if miss[i] <= radius:
            first = i
            break
    if first >= 0:
        j = first
        i = first + 1
        while i < m and miss[i] <= radius:
            if miss[i] < miss[j]:
                j = i
            i += 1
    else:
        j = int(np.argmin(miss))
    return cumulative[j] + ts[j] * (cumulative[j + 1] - cumulative[j]), miss[j]
