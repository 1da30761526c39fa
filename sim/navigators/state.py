"""What a navigator holds over one flight: the mission's commands and the active one, the
aircraft's true state and the estimate it steers, the air it flies through, the flown track and
the events (:class:`NavigatorState`, the base of sim/navigators/base.py's ``Navigator``).

The navigator steers its ESTIMATE of where it is (``est``: the true position plus the INS error
of sim/ins.py when one is given), never the truth; the aircraft (sim/aircraft.py) flies the truth
through the wind (sim/wind.py).
"""

from __future__ import annotations

import math

import numpy as np
from gcs_planner.sim import atmosphere
from gcs_planner.sim.aircraft import AircraftState, Envelope
from gcs_planner.sim.ins import InsEstimate
from gcs_planner.sim.navigators.airframe import POINT_MASS, Airframe
from gcs_planner.sim.navigators.commands import Event, NavCommand
from gcs_planner.sim.navigators.params import AutopilotParams
from gcs_planner.sim.wind import WindField

# On a straight leg where the aircraft is settled on the track and its glide slope in a steady
# air mass, nothing changes but the position, so the step grows COARSE_STEPS times: the long
# legs of a 170 km mission cost little, the turns and the gusts keep the fine step.
DEFAULT_STEP_S = 0.5
COARSE_STEPS = 8
# (t, x, y, z, course, bank, climb, EAS, seq, heading, TAS, ground speed) per step.
SAMPLE_FIELDS = 12


class NavigatorState:
    """The state of mode AUTO over one flight, and the track and events it leaves."""

    def __init__(
        self,
        commands: list[NavCommand],
        airspeed: float,
        ap: AutopilotParams,
        start: AircraftState,
        dt: float,
        *,
        free_turn: bool = False,
        wind: WindField | None = None,
        alt_offset: float = 0.0,
        ins: InsEstimate | None = None,
        airframe: Airframe | None = None,
    ) -> None:
        self.cmds = commands
        # What flies the navigator's demands: the point mass (sim/aircraft.py) unless another
        # flight model is given (sim/jsbsim_airframe.py), the navigator code the same for both.
        self.airframe: Airframe = airframe or POINT_MASS
        self.cruise = airspeed
        self.ap = ap
        self.free_turn = free_turn
        self.dt = dt
        self.wind = wind
        self.alt_offset = alt_offset
        # The INS (sim/ins.py): offset(state) -> (dx, dy, dz) of the estimate from the truth;
        # observe(before, after) after every step (corrections happen there, in the truth).
        self.ins = ins
        self.env = self._envelope(airspeed)
        self.s = start
        if self.s.tas <= 0:
            self.s.tas = self.s.ground_speed = airspeed * self.eas2tas(start.z)
        # The flown track, one row per step (see record), grown by doubling; the compiled
        # flight (sim/flight_kernel.py) writes its steps into the same array.
        self.track = np.empty((4096, SAMPLE_FIELDS))
        self.n_samples = 0
        self.events: list[Event] = []
        self.notes: list[str] = []
        self.k = -1  # index of the active command
        self.est = (start.x, start.y, start.z)
        self.prev = self.est
        self.phase = "track"  # "track" | "loiter" (circling: a loiter item, or PX4 for altitude)
        self.loiter_sum = 0.0
        self.loiter_started = False
        self.loiter_t0 = 0.0
        self.min_dist = math.inf
        self.hold_alt: float | None = None
        self.ended = ""
        self.settled = False  # on the track and the glide slope (see COARSE_STEPS)
        self.alt_error = 0.0
        self.update_estimate()

    # The air and the estimate -------------------------------------------------------------
    def _envelope(self, airspeed: float) -> Envelope:
        bank = 90.0 if self.free_turn else float(self.ap.bank_limit or 45.0)
        climb = float(self.ap.climb_rate or 5.0)
        sink = float(self.ap.sink_rate or 5.0)
        pitch = 90.0 if self.ap.pitch_limit is None else float(self.ap.pitch_limit)
        floor = float(self.ap.ground_speed_floor or 0.0)
        most = float(self.ap.airspeed_max or math.inf)
        return Envelope(float(airspeed), bank, climb, sink, pitch, floor, most)

    def eas2tas(self, z: float) -> float:
        return atmosphere.eas2tas(z + self.alt_offset)

    def update_estimate(self) -> None:
        """The estimate of where the aircraft is, from its true state and the INS."""
        s = self.s
        if self.ins is None:
            self.est = (s.x, s.y, s.z)
        else:
            dx, dy, dz = self.ins.offset(s)
            self.est = (s.x + dx, s.y + dy, s.z + dz)

    def ground_speed(self) -> float:
        """Speed over the ground of the last step: L1 and npfg work on the ground velocity, so
        a headwind (or a steep climb) shortens L1 and slows the turns they ask for."""
        return max(self.s.ground_speed, 1e-3)

    def air(self, dt: float) -> tuple[float, ...]:
        """The air's motion over the next ``dt`` seconds (east, north, and up in turbulence,
        m/s) where the aircraft flies now: still air without a wind field."""
        if self.wind is None:
            return (0.0, 0.0)
        return self.wind.air(dt, self.s.z + self.alt_offset, self.s.tas)

    @property
    def steady_air(self) -> bool:
        """No gusts and no turbulence: the air changes nothing from step to step."""
        return self.wind is None or self.wind.steady

    def _fly(self, lateral: float, climb: float, dt: float, heading: float | None = None) -> None:
        wind = self.air(dt)
        before = self.s
        e2t = self.eas2tas(before.z)
        self.s = self.airframe.step(before, self.env, lateral, climb, dt, wind, e2t, heading)
        self._after(before)

    def _after(self, before: AircraftState) -> None:
        if self.ins is not None:
            self.ins.observe(before, self.s)
        self.update_estimate()

    # The track and the events -------------------------------------------------------------
    def record(self) -> None:
        s = self.s
        seq = self.cmds[self.k].seq if 0 <= self.k < len(self.cmds) else -1
        if self.n_samples >= len(self.track):
            self.reserve(1)
        self.track[self.n_samples] = (
            s.t, s.x, s.y, s.z, s.course, s.bank_deg, s.climb_rate, self.env.airspeed, seq,
            s.heading, s.tas, s.ground_speed,
        )  # fmt: skip
        self.n_samples += 1

    def reserve(self, rows: int) -> None:
        """Room for ``rows`` more samples."""
        need = self.n_samples + rows
        if need > len(self.track):
            grown = np.empty((max(need, 2 * len(self.track)), SAMPLE_FIELDS))
            grown[: self.n_samples] = self.track[: self.n_samples]
            self.track = grown

    @property
    def samples(self) -> np.ndarray:
        """(t, x, y, z, course, bank, climb, EAS, seq, heading, TAS, ground speed) per step."""
        return self.track[: self.n_samples]

    def event(self, seq: int, kind: str, text: str = "") -> None:
        self.events.append(Event(self.s.t, self.n_samples - 1, seq, kind, text))
