"""What a replay reports: the path flown, the landmarks met and missed on it, the corrections
made, one run's outcome, the Monte Carlo summary over many runs, and the report the dry run
prints (sim/replay.py flies and judges them)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from functools import cached_property

import numpy as np
from gcs_planner.sim import flight_kernel, guidance

from gcs_planner.scenario.model import Kind


@dataclass(frozen=True)
class FlightPath:
    """The positions flown through, local frame, A first. ``seqs[i]`` is the mission item of
    point i (-1 for the start)."""

    points: np.ndarray  # (m, 3)
    seqs: tuple[int, ...]
    speeds: tuple[float, ...]  # cruise speed on the segment ending at point i (0 for the start)

    @cached_property
    def cumulative(self) -> np.ndarray:
        seg = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        return np.concatenate([[0.0], np.cumsum(seg)])

    @property
    def length(self) -> float:
        return float(self.cumulative[-1])

    @cached_property
    def contiguous_points(self) -> np.ndarray:
        return np.ascontiguousarray(self.points, dtype=float)

    @cached_property
    def blocks(self) -> np.ndarray:
        """Bounding boxes of its segments (sim/flight_kernel.py track_blocks)."""
        return flight_kernel.track_blocks(self.contiguous_points)

    def position_at(self, distance: float) -> np.ndarray:
        cum = self.cumulative
        if distance <= 0 or len(cum) < 2:
            return self.points[0].copy()
        if distance >= cum[-1]:
            return self.points[-1].copy()
        k = int(np.searchsorted(cum, distance, side="right")) - 1
        span = cum[k + 1] - cum[k]
        t = 0.0 if span <= 0 else (distance - cum[k]) / span
        return self.points[k] + t * (self.points[k + 1] - self.points[k])

    def until(self, distance: float) -> FlightPath:
        """The path up to ``distance`` flown, its last point interpolated."""
        cum = self.cumulative
        k = int(np.searchsorted(cum, distance, side="right"))
        if k >= len(cum):
            return self
        end = self.position_at(distance)
        points = np.vstack([self.points[:k], end[None, :]])
        return FlightPath(points, self.seqs[: k + 1], self.speeds[: k + 1])


@dataclass(frozen=True)
class Encounter:
    """The path passes within the capture radius of a correction point."""

    landmark: int  # index in the scenario
    id: str
    kind: Kind
    unreliable: bool
    distance: float  # flown from A to the closest approach
    miss: float  # closest approach, metres
    seq: int  # the mission item nearest to it


@dataclass(frozen=True)
class Missed:
    """A landmark the mission flies to (a waypoint on it) that the flight did not pass within
    the capture radius of: no correction there."""

    landmark: int
    id: str
    kind: str
    seq: int  # the mission item on it
    distance: float  # flown from A to the closest approach
    miss: float  # 3D closest approach, metres


@dataclass(frozen=True)
class CorrectionRow:
    """One correction of a replay: the errors on arrival (before it) and what it did."""

    id: str
    kind: str
    seq: int
    distance: float
    unreliable: bool
    v_before: float
    h_before: float
    v_limit: float
    h_limit: float
    v_margin: float
    h_margin: float
    within_limits: bool
    succeeded: bool | None  # None when the vehicle was lost on arrival
    v_after: float
    h_after: float
    miss: float = 0.0  # true 3D closest approach to the landmark, metres
    estimate_error_m: float = 0.0  # the INS estimate's distance from the truth there, metres


@dataclass(frozen=True)
class ReplayRun:
    """One replay with drawn outcomes."""

    arrived: bool
    lost: bool
    lost_reason: str
    flown_length: float  # up to the end of the mission, or to where it was lost
    corrections: tuple[CorrectionRow, ...]
    v_at_end: float
    h_at_end: float
    reached_b: bool
    miss_b: float
    missed_before_loss: bool = False  # the flight missed a landmark of the mission before
    # The aircraft's endurance ran out before it came to B (sim/guidance.py ENDURANCE_ENDED).
    out_of_endurance: bool = False

    @property
    def flight_lost(self) -> bool:
        """Lost by the flight: a landmark of the mission missed on the way, the endurance run
        out before B, or a limit passed (or B missed) with no failed correction before it; not
        chance at unreliable points. The vehicle's own coarse rule: the ground station, which
        knows the plan, refines it from ``MonteCarloSummary.lost_runs`` (a plan certain to
        arrive is never lost by its corrections)."""
        if self.arrived:
            return False
        if self.missed_before_loss or self.out_of_endurance:
            return True
        return not any(c.succeeded is False for c in self.corrections)


@dataclass(frozen=True)
class LostRun:
    """A run that was lost: whether its flight had missed a landmark of the mission before, and
    the landmarks (by id) whose correction failed before the loss. The ground station, which
    knows the plan, tells from these whether the plan itself would have been lost with the same
    outcomes (gcs_planner/dryrun/run.py): the vehicle knows only its mission."""

    missed: bool
    failed: tuple[str, ...]
    run: int = -1  # its index among the runs (its draws: (seed, run))
    reason: str = ""  # where it was lost and why (ReplayRun.lost_reason)
    missed_ids: tuple[str, ...] = ()  # the landmarks it missed before its loss
    out_of_endurance: bool = False  # its endurance ran out before B (ReplayRun)


@dataclass(frozen=True)
class MonteCarloSummary:
    runs: int
    successes: int
    success_rate: float
    ci_low: float
    ci_high: float
    confidence: float
    # Runs lost by the flight (ReplayRun.flight_lost) and by failed corrections; ``flown`` True
    # when each run was flown on its own (wind, gusts and the estimate drawn per run), False
    # when the outcomes at unreliable points were drawn over one flight.
    flight_losses: int = 0
    correction_losses: int = 0
    flown: bool = False
    lost_runs: tuple[LostRun, ...] = ()


@dataclass(frozen=True)
class ReplayReport:
    """What the dry run prints: one seeded replay, the path, and the Monte Carlo if asked."""

    run: ReplayRun
    mission_length: float
    waypoints: int
    flight_time_s: float
    capture_radius: float
    theta: float
    monte_carlo: MonteCarloSummary | None = None
    encounters: tuple[Encounter, ...] = field(default=(), repr=False)
    # The flight as flown (the whole of it), the mission's nominal path, and the flown track up
    # to the closest approach to B (or to where it was lost before B): what the INS replay used.
    flight: guidance.Flight | None = field(default=None, repr=False)
    nominal: FlightPath | None = field(default=None, repr=False)
    flown: FlightPath | None = field(default=None, repr=False)
    missed: tuple[Missed, ...] = ()

    @property
    def arrived(self) -> bool:
        return self.run.arrived

    @property
    def flown_length(self) -> float:
        return self.run.flown_length

    def to_dict(self) -> dict:
        out = {
            "arrived": self.run.arrived,
            "lost": self.run.lost,
            "lost_reason": self.run.lost_reason,
            "flown_length": self.run.flown_length,
            "mission_length": self.mission_length,
            "waypoints": self.waypoints,
            "flight_time_s": self.flight_time_s,
            "reached_b": self.run.reached_b,
            "miss_b": self.run.miss_b,
            "v_at_end": self.run.v_at_end,
            "h_at_end": self.run.h_at_end,
            "theta": self.theta,
            "capture_radius": self.capture_radius,
            "flight_ended": self.flight.ended if self.flight is not None else "",
            "corrections": [asdict(c) for c in self.run.corrections],
            "missed": [asdict(m) for m in self.missed],
        }
        if self.monte_carlo is not None:
            out["monte_carlo"] = asdict(self.monte_carlo)
            out["success_rate"] = self.monte_carlo.success_rate
        return out
