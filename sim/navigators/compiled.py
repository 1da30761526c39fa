"""The navigator as the compiled flight (sim/flight_kernel.py) reads and resumes it: which of
its commands and phases the kernel flies, its commands, its autopilot's rules and the flight's
step as records (sim/flight_records.py), its state as the kernel's state vector, and the
navigator resumed from what the kernel flew.
"""

from __future__ import annotations

import numpy as np
from gcs_planner.sim.aircraft import AircraftState
from gcs_planner.sim.flight_records import (
    AIRCRAFT_SIZE,
    MODE_ALTITUDE_LOITER,
    MODE_TRACK,
    S_ALT_ERROR,
    S_MIN_DIST,
    S_SETTLED,
    Commands,
    Flight,
    Rules,
    aircraft_record,
)
from gcs_planner.sim.navigators.base import Navigator
from gcs_planner.sim.navigators.commands import LOITERS, NAV_WAYPOINT
from gcs_planner.sim.navigators.params import DEFAULT_TIME_CONSTANT_S


def compiled_mode(nav: Navigator) -> int | None:
    """What the kernel flies of the navigator's active command: MODE_TRACK tracking a waypoint,
    MODE_ALTITUDE_LOITER circling one for its altitude; None when the kernel flies none of it
    (no turn limit, no active command, a loiter item, an item without a position)."""
    if nav.free_turn or nav.k < 0 or nav.k >= len(nav.cmds):
        return None
    cmd = nav.cmds[nav.k]
    if cmd.command in LOITERS or cmd.pos is None:
        return None
    if nav.phase == "track":
        return MODE_TRACK
    if nav.phase == "loiter" and nav.autopilot.circles_for_altitude:
        return MODE_ALTITUDE_LOITER
    return None


def commands_record(nav: Navigator) -> Commands:
    """The navigator's commands as the kernel reads them (see ``Commands``)."""
    cmds = nav.cmds
    n = len(cmds)
    x, y, z, acceptance = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    seq = np.zeros(n, np.int64)
    has_next = np.zeros(n, bool)
    next_x, next_y = np.zeros(n), np.zeros(n)
    plain = np.zeros(n, bool)
    item_acceptance = nav.autopilot.item_acceptance
    for j, cmd in enumerate(cmds):
        seq[j] = cmd.seq
        if cmd.pos is None:
            continue
        x[j], y[j], z[j] = cmd.pos
        if item_acceptance and cmd.command == NAV_WAYPOINT:
            acceptance[j] = float(int(cmd.params[1]) & 0xFF)
        # Navigator.next_target with command j active.
        after = nav.next_nav_index(j + 1)
        nxt = None if after is None else cmds[after].pos
        if nxt is not None:
            has_next[j], next_x[j], next_y[j] = True, nxt[0], nxt[1]
        plain[j] = cmd.command == NAV_WAYPOINT and nav.flies(cmd)
    return Commands(x, y, z, acceptance, seq, has_next, next_x, next_y, plain)


def rules_record(nav: Navigator) -> Rules:
    """The navigator's autopilot's waypoint rules and the parameters they read."""
    traits, ap = nav.autopilot, nav.ap
    return Rules(
        bool(traits.switches_early),
        bool(traits.circles_for_altitude),
        bool(traits.climbs_at_once),
        float(ap.acceptance_radius),
        float(ap.wp_radius),
        float(ap.loiter_radius),
        float(ap.npfg_period),
        float(ap.npfg_damping),
        float(ap.npfg_switch_multiplier),
        float(ap.altitude_time_constant or DEFAULT_TIME_CONSTANT_S),
    )


def flight_record(nav: Navigator, time_limit: float) -> Flight:
    """What holds over one call of the kernel for the navigator, flying until ``time_limit``."""
    return Flight(
        aircraft_record(nav.env),
        rules_record(nav),
        float(nav.dt),
        float(time_limit),
        float(nav.alt_offset),
    )


def state_vector(
    nav: Navigator,
    gusts: tuple[float, float],
    distance: float,
    turbulence: tuple[float, float] = (0.0, 0.0),
) -> np.ndarray:
    """The kernel's state (sim/flight_records.py ``S_*``) of the navigator, with the gusts'
    (east, north m/s), the metres flown and the vertical turbulence's filter state."""
    s = nav.s
    return np.array([
        s.x, s.y, s.z, s.course, s.t, s.bank_deg, s.climb_rate, s.heading, s.tas,
        s.ground_speed, nav.min_dist, nav.alt_error, 1.0 if nav.settled else 0.0,
        gusts[0], gusts[1], distance, turbulence[0], turbulence[1],
    ])  # fmt: skip


def resume(
    nav: Navigator, state: np.ndarray, k: int, prev: np.ndarray, mode: int, decided: bool
) -> None:
    """The navigator after the kernel flew from its state to ``state``, the active command
    ``k`` from ``prev`` in ``mode``, having ``decided`` something (reached a waypoint, began or
    left circling one)."""
    nav.s = AircraftState(*state[:AIRCRAFT_SIZE].tolist())
    nav.min_dist, nav.alt_error = float(state[S_MIN_DIST]), float(state[S_ALT_ERROR])
    nav.settled = bool(state[S_SETTLED] > 0)
    if decided:
        if k != nav.k:
            # Navigator.advance's resets of the loiter state.
            nav.k = k
            nav.loiter_sum, nav.loiter_started, nav.hold_alt = 0.0, False, None
            x0, y0, z0 = prev.tolist()
            nav.prev = (x0, y0, z0)
        nav.phase = "track" if mode == MODE_TRACK else "loiter"
    nav.update_estimate()
