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
reassociated sum may differ (tests/sim/test_flight_kernel.py flies both).

The kernel reads records (sim/flight_records.py): the aircraft, the autopilot's rules (its
record's traits), the mission's commands, the gusts and the INS, made from the navigator by
sim/navigators/compiled.py; it writes the flight's state vector, the navigator's track rows and
its decisions in place. The formulas are sim/point_mass_kernel.py (the aircraft) and
sim/navigator_kernel.py (the navigators'); this module flies them step by step
(:func:`fly_plain`) and hands the result back to the navigator (:func:`fly_plain_steps`). It
also holds the compiled closest approach of sim/replay.py.
"""

from __future__ import annotations

import math

import numpy as np
from gcs_planner.sim.flight_records import (
    E_KIND,
    E_SAMPLE,
    E_SEQ,
    E_T,
    E_VALUE,
    EVENT_ALTITUDE,
    EVENT_ALTITUDE_REACHED,
    EVENT_NONE,
    EVENT_PASSED,
    EVENT_SIZE,
    EVENT_WITHIN,
    MODE_ALTITUDE_LOITER,
    MODE_TRACK,
    S_ALT_ERROR,
    S_DISTANCE,
    S_GS,
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
    STATE_SIZE,
    STOP_EVENT,
    STOP_FULL,
    STOP_TIME,
    Commands,
    Flight,
    Gusts,
    Ins,
    gusts_record,
    ins_busy,
    ins_record,
    resume_gusts,
)
from gcs_planner.sim.navigator_kernel import (
    acceptance,
    advance,
    altitude_loiter_decision,
    altitude_loiter_demand,
    finish_line,
    flown,
    gust,
    keep_step,
    near_landmark,
    offset,
    record_event,
    track_decision,
    track_demand,
    vertical_gust,
    waypoint_altitude_ok,
)
from gcs_planner.sim.navigators.base import Navigator
from gcs_planner.sim.navigators.commands import Event
from gcs_planner.sim.navigators.compiled import (
    commands_record,
    compiled_mode,
    flight_record,
    resume,
    state_vector,
)
from gcs_planner.sim.point_mass_kernel import eas2tas, max_lateral, step
from numba import njit


@njit(cache=True)
def fly_plain(state: np.ndarray, flight: Flight, cmds: Commands, cmd: int, prev: np.ndarray,
              mode: int, gusts: Gusts, k: int, kv: int, ins: Ins, samples: np.ndarray,
              events: np.ndarray) -> tuple[int, int, int, int, int, int, int]:  # fmt: skip
    """Fly the steps of command ``cmd`` of ``cmds`` and of the plain waypoints after it (module
    docstring) from ``state`` (updated in place) and the leg's start ``prev`` (updated when a
    waypoint is reached), in ``mode``, through ``gusts`` from draw ``k`` (the vertical
    turbulence's from ``kv``), writing one row per step into ``samples`` and one per decision
    into ``events`` (time, sample row, seq, EVENT_*, the distance or altitude error its text
    gives); (steps, next gust draw index, why it stopped: STOP_EVENT, STOP_FULL or STOP_TIME,
    the active command, its mode, events, next turbulence draw index)."""
    new = np.empty(STATE_SIZE)
    aircraft, rules = flight.aircraft, flight.rules
    # The air changes from step to step (no coarse steps).
    gusty = gusts.sigma > 0 or gusts.turbulent
    n = 0
    ne = 0
    e2t_z, e2t = math.nan, 1.0
    # Constant over the call: the roll limit's lateral acceleration, the error's direction.
    max_lat = max_lateral(aircraft.bank_limit)
    cos_h, sin_h = math.cos(ins.h_dir), math.sin(ins.h_dir)
    # The estimate's offset at the distance flown (the end of a kept step is the next start).
    off_d = math.nan
    ox, oy, oz = 0.0, 0.0, 0.0
    while True:
        if n >= samples.shape[0] or ne >= events.shape[0]:
            return n, k, STOP_FULL, cmd, mode, ne, kv
        if state[S_T] >= flight.time_limit:
            return n, k, STOP_TIME, cmd, mode, ne, kv
        # The Python wind field draws the next batch.
        if gusts.sigma > 0 and k + 2 > gusts.normals.shape[0]:
            return n, k, STOP_EVENT, cmd, mode, ne, kv
        if gusts.turbulent and kv + 2 > gusts.vnormals.shape[0]:
            return n, k, STOP_EVENT, cmd, mode, ne, kv
        cx, cy, cz = cmds.x[cmd], cmds.y[cmd], cmds.z[cmd]
        ax, ay = prev[0], prev[1]
        # Navigator.advance flies on to the next command only when it is a plain waypoint;
        # this command's decisions are the kernel's only when it is one itself.
        decides = cmds.plain[cmd]
        advances = decides and cmd + 1 < cmds.plain.shape[0] and cmds.plain[cmd + 1]
        if state[S_DISTANCE] != off_d:
            off_d = state[S_DISTANCE]
            ox, oy, oz = offset(ins, off_d, cos_h, sin_h)
        ex, ey, ez = state[S_X] + ox, state[S_Y] + oy, state[S_Z] + oz
        min_dist, alt_error, settled = state[S_MIN_DIST], state[S_ALT_ERROR], state[S_SETTLED]
        dt = flight.dt
        acc = 0.0
        # EAS2TAS at the state's altitude (one pow saved while the altitude holds).
        if state[S_Z] != e2t_z:
            e2t_z = state[S_Z]
            e2t = eas2tas(e2t_z + flight.alt_offset)
        if mode == MODE_TRACK:
            dist = math.hypot(cx - ex, cy - ey)
            acc = acceptance(state[S_GS], rules, cmds, cmd, prev, e2t)
            if dist <= acc and waypoint_altitude_ok(rules, abs(ez - cz)):
                # Navigator.tick: already there, reached at once without a step.
                if not advances:
                    return n, k, STOP_EVENT, cmd, mode, ne, kv
                record_event(events, ne, state[S_T], n - 1, cmds.seq[cmd], EVENT_WITHIN, dist)
                ne += 1
                cmd = advance(state, cmds, cmd, prev, ex, ey, ez)
                continue
            lateral, climb, dt, min_dist, alt_error, settled = track_demand(
                state, flight, cmds, cmd, prev, ex, ey, ez, dist, acc, gusty
            )
        else:
            lateral, climb = altitude_loiter_demand(state, flight, cmds, cmd, ex, ey, ez, max_lat)
        ux, uy, kn = gust(state[S_UX], state[S_UY], gusts, dt, k)
        wx, wy = gusts.wx + ux, gusts.wy + uy
        w1, w2, wz, kvn = vertical_gust(state[S_W1], state[S_W2], gusts, dt, kv,
                                        state[S_Z] + flight.alt_offset, state[S_TAS])  # fmt: skip
        step(state, aircraft, lateral, climb, dt, wx, wy, wz, e2t, max_lat, new)
        crossed = False
        if mode == MODE_TRACK:
            # Navigator.finish_line before and after, on the estimate's offset of the start.
            fx0 = finish_line(ex, ey, cx, cy, ax, ay)
            nx, ny = new[S_X] + (ex - state[S_X]), new[S_Y] + (ey - state[S_Y])
            fx1 = finish_line(nx, ny, cx, cy, ax, ay)
            if fx0 < 0 <= fx1:
                if not decides:
                    return n, k, STOP_EVENT, cmd, mode, ne, kv
                # Navigator.tick stops the step on the finish line.
                crossed = True
                cut = dt * fx0 / (fx0 - fx1)
                step(state, aircraft, lateral, climb, cut, wx, wy, wz, e2t, max_lat, new)
        if ins.present and near_landmark(state, new, ins.landmarks, ins.capture):
            return n, k, STOP_EVENT, cmd, mode, ne, kv
        distance = flown(state, new)
        off_d = distance
        ox, oy, oz = offset(ins, off_d, cos_h, sin_h)
        ex, ey, ez = new[S_X] + ox, new[S_Y] + oy, new[S_Z] + oz
        if mode == MODE_TRACK:
            event, value = track_decision(rules, cmds, cmd, prev, ex, ey, ez, acc, crossed)
        else:
            event = altitude_loiter_decision(new, rules, cmds, cmd, ex, ey, ez, max_lat)
            value = 0.0
        if event != EVENT_NONE and not (advances or (event == EVENT_ALTITUDE and decides)):
            return n, k, STOP_EVENT, cmd, mode, ne, kv
        # The step is kept.
        keep_step(state, new, min_dist, alt_error, settled, ux, uy, w1, w2, distance, samples[n],
                  aircraft.airspeed, cmds.seq[cmd])  # fmt: skip
        k = kn
        kv = kvn
        n += 1
        if event != EVENT_NONE:
            record_event(events, ne, state[S_T], n - 1, cmds.seq[cmd], event, value)
            ne += 1
            if event == EVENT_ALTITUDE:
                # At the waypoint but off its altitude: circle it.
                mode = MODE_ALTITUDE_LOITER
            else:
                mode = MODE_TRACK
                cmd = advance(state, cmds, cmd, prev, ex, ey, ez)


# The Python side ------------------------------------------------------------------------------
_BUFFER_STEPS = 4096
_EVENT_ROWS = 256

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


def fly_plain_steps(pilot: Navigator, time_limit: float, cache: dict) -> None:
    """Fly the navigator ``pilot``'s plain steps in the kernel (module docstring), if its
    active command and phase are of the kinds the kernel flies; the navigator's state, its
    samples and events, the active command, the wind field's gusts and the INS's distance are
    updated as the Python steps would have. Returns before the first step the Python navigator
    must fly. ``cache`` keeps what holds while the navigator's commands do (the caller empties
    it when they change)."""
    nav = pilot
    mode = compiled_mode(nav)
    if mode is None:
        return
    ins = nav.ins
    if ins is not None and ins_busy(ins):
        return
    wind = nav.wind
    cmds = cache.get("commands")
    if cmds is None:
        cmds = cache["commands"] = commands_record(nav)
    flight = flight_record(nav, time_limit)
    gusts, k, kv = gusts_record(wind)
    ins_now = ins_record(ins, cache)
    state = state_vector(
        nav,
        (0.0, 0.0) if wind is None else (wind.ux, wind.uy),
        0.0 if ins is None else ins.distance,
        (0.0, 0.0) if wind is None else (wind.w1, wind.w2),
    )
    prev = np.array(nav.prev, dtype=float)
    events = cache.get("events")
    if events is None:
        events = cache["events"] = np.empty((_EVENT_ROWS, EVENT_SIZE))
    k_cmd = nav.k
    total = 0
    decided = 0
    while True:
        nav.reserve(_BUFFER_STEPS)
        start = nav.n_samples
        rows = nav.track[start : start + _BUFFER_STEPS]
        n, k, why, k_cmd, mode, ne, kv = fly_plain(
            state, flight, cmds, k_cmd, prev, mode, gusts, k, kv, ins_now, rows, events
        )
        for e in events[:ne].tolist():
            kind = int(e[E_KIND])
            nav.events.append(
                Event(e[E_T], start + int(e[E_SAMPLE]), int(e[E_SEQ]), _EVENT_KINDS[kind],
                      _event_text(kind, e[E_VALUE]))
            )  # fmt: skip
        nav.n_samples += n
        total += n
        decided += ne
        if why != STOP_FULL:
            break
    if total == 0 and decided == 0:
        return
    if wind is not None:
        resume_gusts(wind, state, int(k), int(kv))
    if ins is not None:
        ins.distance = float(state[S_DISTANCE])
    resume(nav, state, k_cmd, prev, mode, decided > 0)


# The closest approach of sim/replay.py ---------------------------------------------------------
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
