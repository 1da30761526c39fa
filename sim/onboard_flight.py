"""The mock ArduPilot's flight with a contingency policy switched on board: its stored mission
(onboard.plan) flown with the applet on its SD card (policy.lua) and no ground link, in simulated
time (docs/flying-policies.md, "Switching on board").

The aircraft, its INS and its corrections are the live flight's (sim/live_flight.py). The
correction sensor's companion reports each fix as it is drawn (the true track leaving the
landmark's capture radius) by writing the applet's parameter (a PARAM_SET on the autopilot's
serial port: ``ScriptHost.write_parameter``), and a landmark its mission flies over and misses
once the item after it is reached; the applet (sim/scripting.py) runs whenever its reschedule
time has come on the flight's clock and acts on the mission through its bindings: a
``mission:set_current_cmd`` restarts the navigator at that item, the leg starting where the
aircraft is (``LiveFlight.set_current``).

The flight advances in the flight model's steps, so the applet runs at the first step that
reaches its next run: a report and the switch it calls for fall in the same step. Nothing
reaches or leaves the ground station from take-off on (``MockVehicle.link_cut``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from gcs_planner.sim.live_flight import Happened, LiveFlight
from gcs_planner.sim.live_vehicle import LiveReport, start_flight
from gcs_planner.sim.scripting import (
    MISSION_COMPLETE,
    MISSION_RUNNING,
    ScriptHost,
)

from gcs_planner.mission.items import MissionItem
from gcs_planner.mission.onboard_report import APPLET_FILE, REPORT_PARAM, point_codes, report_value


@dataclass(frozen=True)
class OnboardReport(LiveReport):
    """A flight switched on board: the live flight's report and what the applet did."""

    applet_error: str | None = None  # why the applet stopped, when it did
    jumps: tuple[tuple[float, int], ...] = ()  # (simulated s, onboard item) set current


class _Autopilot:
    """The mock ArduPilot as the applet's bindings see it (sim/scripting.ScriptVehicle)."""

    def __init__(self, vehicle: Any, flight: LiveFlight) -> None:
        self.vehicle = vehicle
        self.flight = flight

    def mission_state(self) -> int:
        return MISSION_RUNNING if self.flight.going else MISSION_COMPLETE

    def num_commands(self) -> int:
        return len(self.vehicle.mission)

    def get_item(self, index: int) -> MissionItem | None:
        held = self.vehicle.mission
        return held[index] if 0 <= index < len(held) else None

    def current_nav_index(self) -> int:
        return max(self.flight.current, 0)

    def set_current_cmd(self, index: int) -> bool:
        # AP_Mission::set_current_cmd refuses an index past the mission's end.
        if not 0 < index < len(self.vehicle.mission):
            return False
        ok = self.flight.set_current(index)
        if ok:
            self.vehicle._fly_current(index)
        return ok

    def send_text(self, severity: int, text: str) -> None:
        self.vehicle._statustext(text, severity)

    def parameter(self, name: str) -> float | None:
        value = self.vehicle.parameters.get(name)
        return None if value is None else float(value)


def _report(host: ScriptHost, happened: Happened, codes: dict[str, int], met: list[str]) -> None:
    """The companion's reports of what the flight drew since the last step."""
    for c in happened.corrections:
        met.append(c.id)
        if c.succeeded is not None and c.id in codes:
            outcome = "made" if c.succeeded else "FAILED"
            host.write_parameter(REPORT_PARAM, report_value(codes[c.id], outcome))
    for m in happened.missed:
        if m.id in codes:
            host.write_parameter(REPORT_PARAM, report_value(codes[m.id], "MISSED"))


def fly_onboard(vehicle: Any, *, seed: int = 0) -> OnboardReport:
    """Fly ``vehicle``'s stored mission with its applet (``vehicle.applet``, policy.lua's text)
    as fast as the machine goes, the ground link cut from take-off on."""
    scenario = vehicle.scenario
    codes = point_codes(scenario.ids)
    flight = start_flight(vehicle, seed)
    autopilot = _Autopilot(vehicle, flight)
    host = ScriptHost(
        vehicle.applet,
        autopilot,
        name=APPLET_FILE,
        on_error=lambda why: vehicle._statustext(why[:50], 2),
    )
    vehicle.cut_link()  # nothing reaches or leaves the ground station from here on
    vehicle.flying = True
    met: list[str] = []
    try:
        host.run_due(0.0)
        while flight.going and not vehicle._stop.is_set():
            until = flight.time_limit if host.next_run_ms is None else host.next_run_ms / 1000
            until = max(until, flight.t + 1e-3)  # a run that asks for no delay still waits a step
            happened = flight.fly_until(until)
            _report(host, happened, codes, met)
            host.run_due(flight.t * 1000.0)
        _report(host, flight.fly_until(flight.t), codes, met)
        run = flight.run()
    finally:
        vehicle.flying = False
    report = OnboardReport(
        run, flight.pilot.ended, flight.t, tuple(flight.changes), tuple(met),
        tuple(vehicle.mission), flight.track(), tuple(flight.switches),
        applet_error=host.error, jumps=tuple((t / 1000.0, k) for t, k in host.jumps),
    )  # fmt: skip
    vehicle.last_live = report
    return report
