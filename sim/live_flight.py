"""A flight in progress: the mock vehicle flies its mission step by step, and the mission may
change under it (a contingency policy's branch uploaded in flight, docs/model.md "Contingency
policies").

The flight model is the replay's (sim/guidance.py: the autopilot's navigator in mode AUTO, the
compiled plain steps of sim/flight_kernel.py, the INS of sim/ins.py, the wind of sim/wind.py);
what differs is that it is flown up to a given simulated time and then waits, so that what
happened so far (the corrections met, the items reached) can be told as it happens and a new
mission taken from the true state the aircraft is in: its position, heading and speeds, its
INS estimate and errors, the wind and its gusts all carry on. The INS is always the in-flight
one (corrections where the true track passes within the capture radius, drawn when the pass
ends); flown on the truth its estimate error is zero.

What the autopilots do when the mission changes in flight:

* **ArduPilot** writes each uploaded item into its stored mission as it arrives
  (``MissionItemProtocol::handle_mission_count`` truncates the mission to the new count;
  ``MissionItemProtocol_Waypoints::replace_item``/``append_item`` then write in place through
  ``AP_Mission::replace_cmd``/``add_cmd``). The command being flown is a copy in RAM:
  "replacing the current active command will have no effect until the command is restarted"
  (AP_Mission.cpp, ``replace_cmd``); the next one is read from storage when the active one
  completes (``AP_Mission::advance_current_nav_cmd``). So during an upload, and after one that
  failed half way, ArduPlane flies a mix: new items up to where the upload got, old ones after.
  :meth:`LiveFlight.stored_changed` with ``keep_active``.
* **PX4** receives into the storage it is not flying (``MavlinkMissionManager::
  handle_mission_count``: "use inactive storage for transmission") and switches only when the
  upload completes; navigator's ``Mission::update_mission`` then keeps the current index (the
  upload marks no item current) and resets the setpoint triplet, so the aircraft flies the new
  mission's item at that index from where it is. :meth:`LiveFlight.stored_changed` without
  ``keep_active``.
* **Set current** (MISSION_SET_CURRENT or MAV_CMD_DO_SET_MISSION_CURRENT): ArduPlane clears
  ``auto_state.next_wp_crosstrack`` (GCS_Mavlink.cpp, ``handle_mission_set_current`` and
  ``handle_command_do_set_mission_current``) so ``set_next_WP`` starts the new leg at the
  aircraft's own position; PX4's ``Mission::set_current_mission_index`` invalidates the
  previous setpoint ("prevent following previous - current line"). Both: the leg to the new
  current item starts where the aircraft is (:meth:`LiveFlight.set_current`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from gcs_planner.sim import flight_kernel, guidance
from gcs_planner.sim.aircraft import AircraftState
from gcs_planner.sim.ins import InsCorrection, InsEstimate
from gcs_planner.sim.navigators import NAVIGATORS
from gcs_planner.sim.navigators.base import Event, NavCommand
from gcs_planner.sim.replay import FlightPath, ReplayRun, _ins_run, closest_approach, scenario_frame
from gcs_planner.sim.wind import WindField, WindModel
from scipy.spatial import cKDTree

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.aircraft.profile import VehicleProfile
from gcs_planner.mission.items import MissionItem
from gcs_planner.scenario.model import Kind, Scenario


@dataclass(frozen=True)
class MissedFix:
    """A correction landmark a mission item lies on that the flight went past outside the
    capture radius: no fix at all."""

    id: str
    kind: str  # "V" or "H"
    seq: int  # the mission item on it
    miss: float  # the track's 3D closest approach so far, metres


@dataclass(frozen=True)
class Happened:
    """What the flight did since it was last asked: corrections met (in order), items reached,
    the item now current (-1 when the flight is over), landmarks of the mission missed."""

    corrections: tuple[InsCorrection, ...]
    reached: tuple[Event, ...]
    current: int
    missed: tuple[MissedFix, ...] = ()


class LiveFlight:
    """One flight of ``items`` from the scenario's A, flown forward on request."""

    def __init__(
        self,
        items: Sequence[MissionItem],
        scenario: Scenario,
        *,
        flavour: str,
        autopilot: guidance.AutopilotParams,
        profile: VehicleProfile,
        capture_radius: float,
        rng: np.random.Generator,
        navigate_on_estimate: bool = True,
        error_unit: float = 0.1,
        wind: WindModel | None = None,
        dt: float = guidance.DEFAULT_STEP_S,
    ) -> None:
        self.scenario = scenario
        self.params = scenario.params.flown()  # the aircraft is held to the true limits
        self.flavour = flavour
        self.home_at_seq0 = autopilot_for(flavour).home_at_seq0
        self.capture_radius = capture_radius
        self.frame = scenario_frame(scenario)
        a = scenario.xyz[scenario.start]
        self.start = (float(a[0]), float(a[1]), float(a[2]))
        # Flown on the truth, the in-flight INS still finds the corrections; its estimate
        # error is zero.
        self.ins = InsEstimate(
            scenario,
            self.params,
            rng,
            capture_radius=capture_radius,
            error_unit=error_unit if navigate_on_estimate else 0.0,
        )
        cmds = self._commands(items)
        course = None
        if scenario.heading_at_a is not None and math.hypot(*scenario.heading_at_a[:2]) > 0:
            course = math.atan2(scenario.heading_at_a[1], scenario.heading_at_a[0])
        if course is None:
            course = guidance.initial_course(cmds, self.start)
        self.time_limit = guidance.default_time_limit(cmds, self.start, profile, wind)
        field = None if wind is None or wind.still else WindField(wind, profile.cruise_airspeed)
        if profile.turn_radius <= 0:
            # Turning on the spot, the navigator steps 4 * COARSE_STEPS times dt on a straight
            # leg (16 s, 400 m): a correction is drawn when a step ends outside the capture
            # radius, and told then. Here it is told as it happens, within a step of 2 s.
            dt = dt / guidance.COARSE_STEPS
        self.pilot = NAVIGATORS[flavour](
            cmds,
            profile.cruise_airspeed,
            autopilot,
            AircraftState(*self.start, course),
            dt,
            free_turn=profile.turn_radius <= 0,
            wind=field,
            alt_offset=float(self.frame.origin.alt),
            ins=self.ins,
        )
        self.pilot.record()
        self.going = self.pilot.advance()
        # What the autopilot stores; the navigator's commands are these but for the one being
        # flown, which on ArduPilot stays the copy it started (see stored_changed).
        self.stored: list[NavCommand] = list(cmds)
        self._cache: dict = {}  # the kernel's table of the commands: rebuilt when they change
        marks = (scenario.kind == Kind.V) | (scenario.kind == Kind.H)
        self._marks = np.flatnonzero(marks)
        self._mark_tree = cKDTree(scenario.xyz[self._marks]) if self._marks.size else None
        self._pending: list[tuple[int, int]] = []  # (landmark, seq) of items reached, unjudged
        self._missed: set[int] = set()
        self._corrections_told = 0
        self._events_told = 0
        self.changes: list[tuple[float, str]] = []  # (simulated time, what changed), for logs
        # (failed or missed point, metres flown from its fix to the item set current): what a
        # switch cost, against the policy's switch room (core/switch_room.py).
        self.switches: list[tuple[str, float]] = []
        self._missed_at: dict[str, float] = {}  # missed landmark -> distance flown when told
        self.finished = False

    # The stored mission ----------------------------------------------------------------------
    def _commands(self, items: Sequence[MissionItem]) -> list[NavCommand]:
        return guidance.mission_commands(
            items, self.frame, self.start, home_at_seq0=self.home_at_seq0
        )

    @property
    def t(self) -> float:
        return float(self.pilot.s.t)

    @property
    def current(self) -> int:
        p = self.pilot
        return p.cmds[p.k].seq if self.going and 0 <= p.k < len(p.cmds) else -1

    def _index_of(self, cmds: list[NavCommand], seq: int) -> int | None:
        return next((i for i, c in enumerate(cmds) if c.seq == seq), None)

    def stored_changed(self, items: Sequence[MissionItem], *, keep_active: bool) -> None:
        """The autopilot's stored mission is now ``items``. ``keep_active`` (ArduPilot): the
        command being flown stays the copy it started, the others are read from the new
        storage; otherwise (PX4, after a completed upload) the item at the current index is
        read from the new mission and flown from where the aircraft is."""
        if not self.going:
            return
        p = self.pilot
        self.stored = self._commands(items)
        new = list(self.stored)
        seq = p.cmds[p.k].seq
        if keep_active:
            k = self._index_of(new, seq)
            if k is None:  # truncated below the active item: nothing follows it
                new = [*new, p.cmds[p.k]]
                k = len(new) - 1
            else:
                new[k] = p.cmds[p.k]
            p.cmds, p.k = new, k
            self.changes.append((self.t, f"stored mission changed ({len(items)} items)"))
        else:
            k = self._index_of(new, seq)
            p.cmds = new
            self._restart_at(0 if k is None else k)
            self.changes.append((self.t, f"new mission ({len(items)} items), item {self.current}"))
        self._cache = {}

    def set_current(self, seq: int) -> bool:
        """Fly item ``seq`` of the stored mission next, the leg starting where the aircraft is.
        False when there is no such item."""
        if not self.going:
            return False
        k = self._index_of(self.stored, seq)
        if k is None:
            return False
        self.pilot.cmds = list(self.stored)  # the item is read from storage
        self._note_switch()
        self._restart_at(k)
        self._cache = {}
        self.changes.append((self.t, f"current item set to {seq}"))
        return True

    def _note_switch(self) -> None:
        """Record how far the aircraft flew from the latest failed or missed fix to now."""
        fixes = [(c.id, c.distance) for c in self.ins.corrections if c.succeeded is False]
        fixes += list(self._missed_at.items())
        if not fixes:
            return
        pid, at = max(fixes, key=lambda f: f[1])
        if all(pid != done for done, _ in self.switches):
            self.switches.append((pid, float(self.ins.distance - at)))

    def _restart_at(self, k: int) -> None:
        p = self.pilot
        p.prev = p.est  # the leg starts at the aircraft (see the module docstring)
        p.k = k - 1
        self.going = p.advance()

    # Flying ----------------------------------------------------------------------------------
    def fly_until(self, t: float) -> Happened:
        """Fly on to simulated time ``t`` (or the end of the flight) and say what happened."""
        p = self.pilot
        while self.going and p.s.t < t:
            if not p.free_turn:
                flight_kernel.fly_plain_steps(p, min(t, self.time_limit), self._cache)
            if self.ins.lost:
                p.ended = "lost"
                self.going = False
                break
            if p.s.t >= self.time_limit:
                p.ended = "time limit"
                p.event(p.cmds[p.k].seq, "end", f"still flying after {self.time_limit:.0f} s")
                self.going = False
                break
            if p.s.t >= t:
                break
            self.going = p.tick()
        if not self.going and not self.finished:
            self.finished = True
            self.ins.finish()  # passes still open end here
        return self._happened()

    def _happened(self) -> Happened:
        p = self.pilot
        corrections = tuple(self.ins.corrections[self._corrections_told :])
        self._corrections_told = len(self.ins.corrections)
        reached = tuple(e for e in p.events[self._events_told :] if e.kind == "reached")
        self._events_told = len(p.events)
        missed: list[MissedFix] = []
        for e in reached:
            # A landmark is judged once the item after its own is reached (PX4 may count its
            # item reached 56 m early and still pass over the landmark on the next leg).
            missed += self._judge()
            self._pending += self._landmarks_of(e.seq)
        if self.finished:
            missed += self._judge(final=True)
        return Happened(corrections, reached, self.current, tuple(missed))

    def _landmarks_of(self, seq: int) -> list[tuple[int, int]]:
        cmd = next((c for c in self.pilot.cmds if c.seq == seq), None)
        if cmd is None or cmd.pos is None or self._mark_tree is None:
            return []
        near = self._mark_tree.query_ball_point(cmd.pos, r=self.capture_radius)
        return [(int(self._marks[j]), seq) for j in near]

    def _judge(self, final: bool = False) -> list[MissedFix]:
        out, keep = [], []
        for li, seq in self._pending:
            if li in self.ins._used or li in self._missed:
                continue  # its fix was drawn (and told), or its miss told
            if li in self.ins._passes and not final:
                keep.append((li, seq))  # the aircraft is within the radius now
                continue
            _, miss = closest_approach(self.track(), self.scenario.xyz[li], self.capture_radius,
                                       compiled=True)  # fmt: skip
            kind = Kind(int(self.scenario.kind[li])).name
            out.append(MissedFix(self.scenario.ids[li], kind, seq, float(miss)))
            # Told now, so a switch on it counts from here (its closest approach is behind).
            self._missed_at[self.scenario.ids[li]] = float(self.ins.distance)
            self._missed.add(li)  # told once
        self._pending = keep
        return out

    # The verdict -----------------------------------------------------------------------------
    def track(self) -> FlightPath:
        s = self.pilot.samples
        points = np.ascontiguousarray(s[:, 1:4], dtype=float)
        return FlightPath(points, tuple(s[:, 8].astype(int).tolist()), tuple(s[:, 7].tolist()))

    def run(self) -> ReplayRun:
        """The run as the replay judges one (sim/replay.py): up to the closest approach to B,
        which must be within the capture radius with both errors within theta."""
        sc = self.scenario
        track = self.track()
        if len(track.points) < 2:
            track = FlightPath(np.vstack([track.points, track.points]), (-1, -1), (0.0, 0.0))
        b_distance, b_miss = closest_approach(
            track, sc.xyz[sc.end], self.capture_radius, compiled=True
        )
        if self.pilot.ended == "lost" and b_miss > self.capture_radius:
            # Lost at a landmark before B: the run is the flight up to its loss, as the replay
            # judges it (sim/replay.py): its closest approach to B so far may lie far back.
            path = track
        else:
            path = track.until(b_distance)
        run, _ = _ins_run(self.ins, path, sc, self.params, self.capture_radius)
        return run

    def sample(self) -> np.ndarray:
        """The last sample: (t, x, y, z, course, bank, climb, EAS, seq, heading, TAS, gs)."""
        return self.pilot.samples[-1]


def passed_within(
    track: FlightPath, scenario: Scenario, ids: Sequence[str], radius: float
) -> dict[str, float]:
    """The 3D closest approach of ``track`` to each landmark of ``ids``."""
    out = {}
    index = {pid: i for i, pid in enumerate(scenario.ids)}
    for pid in ids:
        i = index.get(pid)
        if i is None or Kind(int(scenario.kind[i])) not in (Kind.V, Kind.H, Kind.B):
            continue
        _, miss = closest_approach(track, scenario.xyz[i], radius, compiled=True)
        out[pid] = float(miss)
    return out
