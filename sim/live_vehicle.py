"""The mock vehicle's flight when its mission may change in flight (``MockVehicle(live=True)``):
the aircraft flies on at ``time_scale`` simulated seconds per wall second while the ground
station talks to it, and takes what the ground station uploads and sets as a real autopilot
does (sim/live_flight.py).

Time is honest: the simulated clock is the wall clock times ``time_scale`` from the moment the
flight starts, whatever the link does. An upload that takes 2 s of wall time at a time scale of
20 costs 40 s of flight, about 1 km at 25 m/s: a ground station that switches missions after a
failed fix has, as its window, the distance from that fix to the next item of the mission
flown (the aircraft then turns to whatever it holds) divided by the ground speed and by the
time scale. Changes are taken at the next wall tick (1/``POSITION_RATE_HZ`` s): the aircraft
flies on up to ``time_scale`` / 10 s meanwhile, as an autopilot's 10 Hz mission loop lags by a
cycle.

The telemetry is the replayed flight's (sim/telemetry.py): HEARTBEAT armed in AUTO while
flying, GLOBAL_POSITION_INT / ATTITUDE / VFR_HUD at 10 Hz of wall time, MISSION_CURRENT when
the item changes, MISSION_ITEM_REACHED, and the correction reports of
gcs_planner/link/correction_report.py the moment each correction is drawn (when the true track
leaves the landmark's capture radius). The flight ends at the mission's end (the loiter at B),
when the INS is lost, or at the time limit; its verdict is the replay's (``LiveFlight.run``).
"""

from __future__ import annotations

import queue
import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from gcs_planner.sim import telemetry
from gcs_planner.sim.guidance import AutopilotParams
from gcs_planner.sim.ins import InsCorrection
from gcs_planner.sim.live_flight import Happened, LiveFlight
from gcs_planner.sim.replay import FlightPath, ReplayRun, scenario_frame

from gcs_planner.link.connection import mavlink
from gcs_planner.link.correction_report import format_report
from gcs_planner.link.protocol import DEFAULT_TIMEOUT_S

DEFAULT_TIME_SCALE = 20.0
# A correction report is a STATUSTEXT, which no one acknowledges: it goes out this many times,
# this many wall seconds apart (docs/flying-policies.md); the ground station takes the
# first copy (a landmark is used once per flight). At 5 % loss each way one report in 8000 is
# lost all three times.
REPORT_COPIES = 3
REPORT_REPEAT_S = 0.5


@dataclass(frozen=True)
class LiveReport:
    """A flight flown live: its verdict, the missions it held, the corrections it met."""

    run: ReplayRun
    ended: str
    flight_time_s: float
    changes: tuple[tuple[float, str], ...]
    points_met: tuple[str, ...]  # correction landmarks the flight used, in order
    final_mission: tuple[Any, ...]  # the items stored when it ended
    track: FlightPath | None = None  # the flown track (local frame)
    # (failed or missed point, metres flown from its fix to the branch's item set current)
    switches: tuple[tuple[str, float], ...] = ()

    @property
    def arrived(self) -> bool:
        return self.run.arrived


class _Samples:
    """One sample of a live flight in the shape telemetry.position_messages reads."""

    def __init__(self, row: np.ndarray) -> None:
        self.xyz = row[None, 1:4]
        self.course, self.bank, self.climb = row[None, 4], row[None, 5], row[None, 6]
        self.airspeed = row[None, 7]


# With a cruise time scale (``MockVehicle.cruise_speedup``), the flight advances at most this many
# simulated seconds between looks for a failed or missed fix, so that the honest time scale
# starts within this much flight of the fix (25 m at 25 m/s: the report of a failed fix comes
# late by at most that, which the policy's switch room must absorb too).
CRUISE_STEP_S = 1.0
# The honest window after a failed or missed fix closes when the ground station sets an item
# current, at the next correction, or after this long (simulated).
WINDOW_MAX_S = 1800.0
# After the ground station sets an item current, the honest scale holds until it has been
# quiet this many wall seconds: a DO_SET_MISSION_CURRENT whose acknowledgement was lost is sent
# again after the ground station's timeout (gcs_planner/link/protocol.py, 1.5 s), and a copy
# taken at the cruise scale would find the aircraft a thousand seconds further on and turn it
# back to the item set (run 59 of docs/flying-policies.md's 400-run dry run: an item set
# current 14.3 km on).
SETTLE_WALL_S = 2 * DEFAULT_TIMEOUT_S


@dataclass
class _Window:
    """After a failed or missed fix, while the ground station may act, or after it acted, until
    it is quiet (``quiet_until``, wall seconds): the honest time scale."""

    since: float  # simulated seconds
    quiet_until: float | None = None  # wall seconds; None: a window opened by a fix

    def over(self, flight: LiveFlight, t: float, happened: Any, now: float) -> bool:
        if self.quiet_until is not None:
            return now >= self.quiet_until or t - self.since > WINDOW_MAX_S
        return flight.current < 0 or bool(happened.corrections) or t - self.since > WINDOW_MAX_S

    def settling(self) -> bool:
        return self.quiet_until is not None


def _fly_to(
    flight: LiveFlight, t0: float, target: float, cruising: bool, watch: frozenset[str] | None
) -> tuple[Any, float, bool]:
    """Fly from simulated ``t0`` to ``target``: in one go at the honest scale, in steps of
    CRUISE_STEP_S while cruising, stopping at the step where a watched fix fails or a watched
    landmark is missed (``watch`` None: any). Returns (what happened, the time reached,
    whether such a fix stopped it)."""
    if not cruising:
        happened = flight.fly_until(target)
        return happened, target, _needs_window(happened, watch)
    parts = []
    t = t0
    opened = False
    while t < target and flight.going:
        t = min(target, t + CRUISE_STEP_S)
        part = flight.fly_until(t)
        parts.append(part)
        if _needs_window(part, watch):
            opened = True
            break
    if not parts:
        parts.append(flight.fly_until(t))
    merged = Happened(
        tuple(c for p in parts for c in p.corrections),
        tuple(e for p in parts for e in p.reached),
        parts[-1].current,
        tuple(m for p in parts for m in p.missed),
    )
    return merged, t, opened


def _needs_window(happened: Any, watch: frozenset[str] | None) -> bool:
    """Whether a fix failed or a landmark was missed where the ground station may act."""
    ids = [m.id for m in happened.missed]
    ids += [c.id for c in happened.corrections if c.succeeded is False]
    return any(watch is None or i in watch for i in ids)


def report_text(c: InsCorrection, delta: float) -> tuple[str, int]:
    """The STATUSTEXT and severity of one correction."""
    if c.succeeded is None:
        outcome, severity = "LOST", mavlink.MAV_SEVERITY_CRITICAL
    elif c.succeeded:
        outcome, severity = "made", mavlink.MAV_SEVERITY_INFO
    else:
        outcome, severity = "FAILED", mavlink.MAV_SEVERITY_WARNING
    detail = f"v{c.v_before_m * delta:.1f} h{c.h_before_m * delta:.1f}"
    return format_report(c.kind.name, c.id, outcome, detail), severity


def _announce(
    vehicle: Any, happened: Any, delta: float, now: float, met: list[str], repeats: list[list]
) -> None:
    """Tell the ground station what the flight did since the last tick: the items reached, the
    corrections drawn and the landmarks missed, each report then sent again REPORT_COPIES - 1
    times (``repeats``: [(text, severity), when next, copies left]); ``met`` gathers the
    correction landmarks."""
    for e in happened.reached:
        vehicle._send(vehicle.mav.mission_item_reached_encode(e.seq))
    for c in happened.corrections:
        met.append(c.id)
        text = report_text(c, delta)
        vehicle._statustext(*text)
        repeats.append([text, now + REPORT_REPEAT_S, REPORT_COPIES - 1])
    for m in happened.missed:
        text = (format_report(m.kind, m.id, "MISSED", f"by {m.miss:.1f}m"),
                mavlink.MAV_SEVERITY_WARNING)  # fmt: skip
        vehicle._statustext(*text)
        repeats.append([text, now + REPORT_REPEAT_S, REPORT_COPIES - 1])
    for r in repeats:
        if r[2] > 0 and now >= r[1]:
            vehicle._send_statustext_copy(*r[0])
            r[1], r[2] = now + REPORT_REPEAT_S, r[2] - 1


def start_flight(vehicle: Any, seed: int) -> LiveFlight:
    """The flight of ``vehicle``'s stored mission (a sim.vehicle.MockVehicle with a scenario)
    from A, with its parameters, wind and landmark database."""
    scenario = vehicle.scenario
    return LiveFlight(
        vehicle.mission,
        scenario,
        flavour=vehicle.flavour,
        autopilot=AutopilotParams.from_parameters(vehicle.flavour, vehicle.parameters),
        profile=replace(scenario.vehicle, cruise_airspeed=vehicle.cruise_speed),
        capture_radius=vehicle.capture_radius,
        rng=np.random.default_rng(seed),
        navigate_on_estimate=vehicle.navigate_on_estimate,
        wind=vehicle.wind,
    )


def fly_live(vehicle: Any, *, seed: int = 0, time_scale: float | None = None) -> LiveReport:
    """Fly ``vehicle``'s stored mission (a sim.vehicle.MockVehicle with a scenario), taking the
    uploads and set-current commands that arrive meanwhile."""
    scenario = vehicle.scenario
    scale = float(time_scale or vehicle.speedup or DEFAULT_TIME_SCALE)
    server = vehicle.missions
    changes: queue.SimpleQueue = queue.SimpleQueue()
    flight = start_flight(vehicle, seed)
    frame = scenario_frame(scenario)
    delta = flight.params.delta
    met: list[str] = []
    repeats: list[list] = []  # [(text, severity), when next, copies left]
    server.listener = changes.put
    server.in_flight = True
    # ArduPilot writes uploaded items in place (see sim/live_flight.py); PX4 switches storage.
    server.in_place = server.protocol.writes_in_place
    vehicle.flying = True
    vehicle._heartbeat()
    boot = last = time.monotonic()
    last_current = -2
    cruise = getattr(vehicle, "cruise_speedup", None)
    cruise = scale if cruise is None else max(float(cruise), scale)
    # The landmarks whose failed or missed fix the ground station acts on (None: any).
    watch = getattr(vehicle, "watch_points", None)
    # How long the honest scale outlasts a set-current (a ground station may set its own:
    # policies/dry_run.py, from its timeout).
    settle = float(getattr(vehicle, "settle_wall_s", SETTLE_WALL_S))
    sim_t = 0.0
    window: _Window | None = None
    try:
        while not vehicle._stop.is_set():
            now = time.monotonic()
            target = sim_t + (now - last) * (scale if window is not None else cruise)
            last = now
            happened, sim_t, opened = _fly_to(
                flight, sim_t, target, window is None and cruise > scale, watch
            )
            if window is not None and window.over(flight, sim_t, happened, now):
                window = None
            if opened and (window is None or window.settling()):
                window = _Window(sim_t)  # a new failure: the ground station may act again
            _announce(vehicle, happened, delta, now, met, repeats)
            while True:
                try:
                    what, value = changes.get_nowait()
                except queue.Empty:
                    break
                if what == "stored":
                    flight.stored_changed(value, keep_active=server.in_place)
                elif what == "current":
                    flight.set_current(value)
                    # The ground station has acted: back to the cruise scale once it is quiet
                    # (a resent set-current lands in honest time).
                    window = _Window(sim_t, quiet_until=now + settle)
            if flight.current >= 0 and flight.current != last_current:
                last_current = flight.current
                vehicle._fly_current(last_current)
            for msg in telemetry.position_messages(
                vehicle.mav, frame, _Samples(flight.sample()), 0, boot
            ):
                vehicle._send(msg)
            if not flight.going:
                break
            vehicle._stop.wait(1.0 / telemetry.POSITION_RATE_HZ)
        last = flight.fly_until(flight.t)  # any told by the last step
        for c in last.corrections:
            met.append(c.id)
            vehicle._statustext(*report_text(c, delta))
        for m in last.missed:
            vehicle._statustext(format_report(m.kind, m.id, "MISSED", f"by {m.miss:.1f}m"),
                                mavlink.MAV_SEVERITY_WARNING)  # fmt: skip
        run = flight.run()
        if not run.arrived:
            reason = run.lost_reason or "did not arrive"
            vehicle._statustext(f"INS LOST: {reason}"[:50], mavlink.MAV_SEVERITY_CRITICAL)
    finally:
        server.listener = None
        server.in_flight = False
        server.in_place = False
        vehicle.flying = False
        vehicle._heartbeat()
    report = LiveReport(
        run, flight.pilot.ended, flight.t, tuple(flight.changes), tuple(met),
        tuple(vehicle.mission), flight.track(), tuple(flight.switches),
    )  # fmt: skip
    vehicle.last_live = report
    return report
