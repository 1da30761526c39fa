"""Telemetry of a flight, as a ground station sees an autopilot in mode AUTO.

While flying: HEARTBEAT armed in AUTO (ArduPlane custom mode 10; PX4 main mode AUTO, sub mode
MISSION), GLOBAL_POSITION_INT, ATTITUDE and VFR_HUD from the flight model's samples,
MISSION_CURRENT when the active item changes, MISSION_ITEM_REACHED when the autopilot counts an
item reached, and a STATUSTEXT for each correction (made, failed, missed) and when the INS is
lost. In fast-forward (``time_scale`` None) the flight is sent at once with at most
``position_messages`` positions; otherwise paced at ``time_scale`` simulated seconds per wall
second (``--speedup N``; 1 is real time), positions at 10 Hz of wall time.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from gcs_planner.aircraft.autopilot import (
    ARDUPLANE_MODE_AUTO,
    PX4_MAIN_MODE_AUTO,
    PX4_MODE_AUTO_MISSION,
    PX4_SUB_MODE_AUTO_MISSION,
    autopilot_for,
)
from gcs_planner.scenario.georef import LocalFrame

# MAVLink enum values (common.xml / ardupilotmega.xml / PX4's px4_custom_mode.h).
MAV_TYPE_FIXED_WING = 1
MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
MAV_MODE_FLAG_AUTO_ENABLED = 4
MAV_MODE_FLAG_GUIDED_ENABLED = 8
MAV_MODE_FLAG_STABILIZE_ENABLED = 16
MAV_MODE_FLAG_SAFETY_ARMED = 128
MAV_STATE_STANDBY = 3
MAV_STATE_ACTIVE = 4
MAV_SEVERITY_CRITICAL = 2
MAV_SEVERITY_WARNING = 4
MAV_SEVERITY_INFO = 6
# The mission modes' numbers live in the autopilot records (gcs_planner/aircraft/autopilot.py);
# named
# here too for the readers of this module.
__all__ = [
    "ARDUPLANE_MODE_AUTO", "PX4_MAIN_MODE_AUTO", "PX4_MODE_AUTO_MISSION",
    "PX4_SUB_MODE_AUTO_MISSION", "extended_sys_state", "heartbeat_fields", "play", "timeline",
]  # fmt: skip
POSITION_RATE_HZ = 10.0
# EXTENDED_SYS_STATE (common.xml): MAV_VTOL_STATE_UNDEFINED = 0 (not a VTOL);
# MAV_LANDED_STATE_ON_GROUND = 1, MAV_LANDED_STATE_IN_AIR = 2.
MAV_VTOL_STATE_UNDEFINED = 0
MAV_LANDED_STATE_ON_GROUND = 1
MAV_LANDED_STATE_IN_AIR = 2


def heartbeat_fields(flavour: str, flying: bool) -> tuple[int, int, int, int, int]:
    """(type, autopilot, base_mode, custom_mode, system_status) of the vehicle's HEARTBEAT."""
    record = autopilot_for(flavour)
    autopilot = record.autopilot_id
    if not flying:
        standby = MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        return MAV_TYPE_FIXED_WING, autopilot, standby, 0, MAV_STATE_STANDBY
    base = (
        MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        | MAV_MODE_FLAG_SAFETY_ARMED
        | MAV_MODE_FLAG_AUTO_ENABLED
        | MAV_MODE_FLAG_GUIDED_ENABLED
        | MAV_MODE_FLAG_STABILIZE_ENABLED
    )
    return MAV_TYPE_FIXED_WING, autopilot, base, record.auto_custom_mode, MAV_STATE_ACTIVE


def extended_sys_state(flying: bool) -> tuple[int, int]:
    """(vtol_state, landed_state) of EXTENDED_SYS_STATE: the mock's aircraft is on the ground
    until a flight starts, in the air while it plays, and on the ground again after it (the
    mock ends a flight where the replay ends; it does not model the loiter left at B)."""
    landed = MAV_LANDED_STATE_IN_AIR if flying else MAV_LANDED_STATE_ON_GROUND
    return MAV_VTOL_STATE_UNDEFINED, landed


@dataclass(frozen=True)
class Moment:
    """Something to tell the ground station at simulated time ``t``."""

    t: float
    order: int  # ties: current before reached before corrections before loss
    kind: str  # "current" | "reached" | "status"
    seq: int = -1
    text: str = ""
    severity: int = MAV_SEVERITY_INFO


def timeline(report: Any) -> list[Moment]:
    """The moments of a replay (sim/replay.ReplayReport with its flight), in time order, up to
    the end of the replay (B, or where the INS was lost)."""
    flight = report.flight
    cum = report.flown.cumulative if report.flown is not None else flight.cumulative
    t_end = float(np.interp(report.run.flown_length, cum, flight.t[: len(cum)]))
    out: list[Moment] = []
    last = None
    for t, seq in zip(flight.t, flight.current, strict=True):
        if t > t_end:
            break
        if seq != last and seq >= 0:
            out.append(Moment(float(t), 0, "current", int(seq)))
            last = seq
    for e in flight.events:
        if e.kind == "reached" and e.t <= t_end:
            out.append(Moment(e.t, 1, "reached", e.seq))
    for row in report.run.corrections:
        t = float(np.interp(row.distance, cum, flight.t[: len(cum)]))
        if row.succeeded is None:
            what, sev = "LOST", MAV_SEVERITY_CRITICAL
        else:
            what, sev = ("made", MAV_SEVERITY_INFO) if row.succeeded else ("FAILED", 4)
        text = f"{row.kind} fix {row.id} {what} v{row.v_before:.1f} h{row.h_before:.1f}"
        out.append(Moment(t, 2, "status", row.seq, text, sev))
    for miss in getattr(report, "missed", ()):
        t = float(np.interp(miss.distance, cum, flight.t[: len(cum)]))
        if t <= t_end:
            text = f"{miss.kind} fix {miss.id} MISSED by {miss.miss:.1f}m"
            out.append(Moment(t, 2, "status", miss.seq, text, MAV_SEVERITY_WARNING))
    if not report.run.arrived:
        reason = report.run.lost_reason or "lost"
        out.append(Moment(t_end, 3, "status", -1, f"INS LOST: {reason}", MAV_SEVERITY_CRITICAL))
    out.sort(key=lambda m: (m.t, m.order))
    return out


def position_messages(mav: Any, frame: LocalFrame, flight: Any, i: int, boot: float) -> list:
    """GLOBAL_POSITION_INT, ATTITUDE and VFR_HUD of sample ``i``."""
    x, y, z = flight.xyz[i]
    lat, lon, alt = frame.to_geodetic(x, y, z)
    course = float(flight.course[i])
    v = float(flight.airspeed[i])
    vz = float(flight.climb[i])
    vh = math.sqrt(max(v * v - vz * vz, 0.0))
    north, east = vh * math.sin(course), vh * math.cos(course)
    heading = (90.0 - math.degrees(course)) % 360.0  # compass: clockwise from north
    ms = int((time.monotonic() - boot) * 1000) & 0xFFFFFFFF
    yaw = math.radians(heading if heading <= 180 else heading - 360)
    pitch = math.asin(max(-1.0, min(1.0, vz / v))) if v > 0 else 0.0
    return [
        mav.global_position_int_encode(
            ms,
            round(lat * 1e7),
            round(lon * 1e7),
            round(alt * 1000),
            round((alt - frame.origin.alt) * 1000),
            round(north * 100),
            round(east * 100),
            round(-vz * 100),
            round(heading * 100) % 36000,
        ),
        mav.attitude_encode(ms, math.radians(float(flight.bank[i])), pitch, yaw, 0.0, 0.0, 0.0),
        mav.vfr_hud_encode(v, vh, round(heading) % 360, 50, float(alt), vz),
    ]


def play(
    report: Any,
    frame: LocalFrame,
    send: Callable[[Any], None],
    mav: Any,
    *,
    statustext: Callable[[str, int], None],
    set_current: Callable[[int], None],
    stop: threading.Event,
    time_scale: float | None = None,
    max_positions: int = 100,
) -> None:
    """Send the flight of ``report`` (a ReplayReport with its flight) as telemetry."""
    flight = report.flight
    moments = timeline(report)
    cum = report.flown.cumulative
    end_t = float(np.interp(report.run.flown_length, cum, flight.t[: len(cum)]))
    last_sample = int(np.searchsorted(flight.t, end_t, side="right")) - 1
    boot = time.monotonic()
    k = 0

    def tell(upto: float) -> None:
        nonlocal k
        while k < len(moments) and moments[k].t <= upto:
            m = moments[k]
            if m.kind == "current":
                set_current(m.seq)
            elif m.kind == "reached":
                send(mav.mission_item_reached_encode(m.seq))
            else:
                statustext(m.text, m.severity)
            k += 1

    if time_scale is None:
        count = max(min(max_positions, last_sample + 1), 1)
        for i in np.linspace(0, last_sample, count).round().astype(int):
            if stop.is_set():
                return
            tell(float(flight.t[i]))
            for msg in position_messages(mav, frame, flight, int(i), boot):
                send(msg)
            time.sleep(0.002)  # let a ground station's socket keep up
        tell(math.inf)
        return
    start = time.monotonic()
    while not stop.is_set():
        sim_t = min((time.monotonic() - start) * time_scale, end_t)
        tell(sim_t)
        i = min(int(np.searchsorted(flight.t, sim_t, side="right")) - 1, last_sample)
        for msg in position_messages(mav, frame, flight, max(i, 0), boot):
            send(msg)
        if sim_t >= end_t:
            tell(math.inf)
            return
        stop.wait(1.0 / POSITION_RATE_HZ)
