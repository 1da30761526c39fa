"""The replay: the mock vehicle flies the mission it stored, with INS drift and corrections.

Inputs are what the vehicle has, never the planner's objects: the MAVLink items it stored, and its
own landmark database (a scenario loaded on its own: the correction points, A where it stands,
B where it must arrive, and the error model's parameters).

Flight. The vehicle flies its stored mission in mode AUTO as its autopilot would
(sim/guidance.py: ArduPlane or PX4 waypoint logic, L1 guidance, loiters) with the aircraft of
sim/aircraft.py: the scenario's vehicle profile (cruise airspeed, turning radius, climb and
descent limits), whatever leg model planned the route. The flown track is what the INS sees.
The mission's own path (straight chords from item to item, ``decode_path``) is kept as the
nominal path the report compares the flight with: a chord under an arc of angle a is shorter
than the arc by the factor sin(a/2)/(a/2), at most 0.33 % for the exporter's 16 degree steps,
plus 2 cm per waypoint for the degE7 quantisation of latitude/longitude.

Error model (docs/model.md). Every metre flown adds delta to both errors. Whenever the flown track
passes within ``capture_radius`` (3D: the landmark's CAPTURE radius, not the autopilot's waypoint
ACCEPTANCE radius) of a correction point of the database that has not been used yet, the
vehicle arrives there: the limits of that kind must hold (else the vehicle is lost), then the
point corrects its component; an unreliable point fails with probability 1 - p, and the
component becomes min(component, r). The vehicle must pass within ``capture_radius`` of B with
both errors <= theta; the replay ends at its closest approach to B, or where a flight on the
INS estimate was lost before it came to B (its closest approach to B so far says nothing of the
landmarks it met after it). Errors are kept in metres
flown since the last reset, as the planner keeps them, and compared with ``Parameters.limits_m``.

Flown on the truth in still air, the path and the corrections it meets do not depend on chance,
only the outcomes at unreliable points do; so a Monte Carlo over N replays draws N outcome
vectors over the same encounters. Flown on the INS estimate (``navigate_on_estimate``, sim/ins.py:
corrections happen in flight where the TRUE track passes within the capture radius, and reset
the estimate) or in wind, every flight depends on its draws, and each run is flown on its own
(``monte_carlo_flights``). A run is lost by the flight (``ReplayRun.flight_lost``) when it missed
a landmark of its mission on the way, or passed a limit or missed B with no failed correction
before it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property

import numpy as np
from scipy.spatial import cKDTree

from gcs_planner.aircraft.profile import (
    DEFAULT_CAPTURE_RADIUS_M,
    DEFAULT_CRUISE_AIRSPEED,
    VehicleProfile,
)
from gcs_planner.dryrun.confidence import wilson_interval
from gcs_planner.mission.items import (
    GLOBAL_AMSL_FRAMES,
    GLOBAL_RELATIVE_FRAMES,
    POSITION_COMMANDS,
    MissionItem,
)
from gcs_planner.scenario.georef import DEFAULT_ORIGIN, LocalFrame
from gcs_planner.scenario.model import Kind, Parameters, Scenario
from sim import flight_kernel, guidance
from sim.ins import DEFAULT_ERROR_UNIT_M, InsEstimate
from sim.wind import WindModel, WindSpec

MAV_CMD_DO_CHANGE_SPEED = 178

DEFAULT_CRUISE_SPEED = DEFAULT_CRUISE_AIRSPEED  # m/s
DENSIFY_MAX_DEG = 16.0
# Largest relative shortfall of a chord under an arc of DENSIFY_MAX_DEG (see module docstring).
CHORD_SHORTFALL = 1.0 - math.sin(math.radians(DENSIFY_MAX_DEG) / 2) / (
    math.radians(DENSIFY_MAX_DEG) / 2
)
QUANTISATION_M = 0.02  # per waypoint: 1e-7 degree is at most 1.1 cm on each axis


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

    @property
    def flight_lost(self) -> bool:
        """Lost by the flight: a landmark of the mission missed on the way, or a limit passed
        (or B missed) with no failed correction before it; not chance at unreliable points.
        The vehicle's own coarse rule: the ground station, which knows the plan, refines it
        from ``MonteCarloSummary.lost_runs`` (a plan certain to arrive is never lost by its
        corrections)."""
        if self.arrived:
            return False
        return self.missed_before_loss or not any(c.succeeded is False for c in self.corrections)


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


def scenario_frame(scenario: Scenario) -> LocalFrame:
    """The vehicle's local frame: the scenario's origin, or the project's default one."""
    return LocalFrame(scenario.origin or DEFAULT_ORIGIN)


def decode_path(
    items: Sequence[MissionItem],
    scenario: Scenario,
    *,
    home_at_seq0: bool = False,
    home_alt: float | None = None,
    cruise_speed: float = DEFAULT_CRUISE_SPEED,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    frame: LocalFrame | None = None,
) -> FlightPath:
    """The path of the stored mission in the scenario's local frame, starting at A.

    ``home_at_seq0``: item 0 is the home position (ArduPilot), not a place to fly to.
    Altitudes of relative frames are above ``home_alt``, by default the altitude of home, which
    is where the vehicle stands: A.

    The flight ends at the first waypoint within ``capture_radius`` of B: what the mission does
    after B (loiter, land, return) is not part of the route and is not flown.
    """
    frame = frame or scenario_frame(scenario)
    a = np.asarray(scenario.xyz[scenario.start], float)
    base_alt = float(a[2] + frame.origin.alt) if home_alt is None else home_alt
    points = [a]
    seqs = [-1]
    speeds = [0.0]
    speed = cruise_speed
    for item in items:
        if home_at_seq0 and item.seq == 0:
            continue
        if item.command == MAV_CMD_DO_CHANGE_SPEED and item.param2 > 0:
            speed = float(item.param2)
            continue
        if item.command not in POSITION_COMMANDS:
            continue
        if item.frame in GLOBAL_AMSL_FRAMES:
            alt = item.z
        elif item.frame in GLOBAL_RELATIVE_FRAMES:
            alt = item.z + base_alt
        else:
            continue  # no position the replay can place (the vehicle refuses such frames)
        # MissionItem holds degE7 whatever the frame's spelling (items.py).
        x, y, z = frame.to_local(item.x / 1e7, item.y / 1e7, alt)
        points.append(np.array([x, y, z]))
        seqs.append(item.seq)
        speeds.append(speed)
        if np.linalg.norm(points[-1] - scenario.xyz[scenario.end]) <= capture_radius:
            break
    return FlightPath(np.vstack(points), tuple(seqs), tuple(speeds))


def _segment_distances(
    path: FlightPath, point: np.ndarray, segs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(miss, t) of ``point`` to the path's segments ``segs`` (index of their first point)."""
    p = path.points[segs]
    d = path.points[segs + 1] - p
    len2 = np.einsum("ij,ij->i", d, d)
    rel = point - p
    t = np.where(len2 > 0, np.einsum("ij,ij->i", rel, d) / np.where(len2 > 0, len2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(rel - t[:, None] * d, axis=1), t


def _first_pass(
    path: FlightPath, point: np.ndarray, segs: np.ndarray, radius: float
) -> tuple[float, float] | None:
    """(distance flown, miss) at the closest approach of the first pass within ``radius`` of
    ``point`` over the candidate segments ``segs`` (sorted), or None."""
    miss, t = _segment_distances(path, point, segs)
    inside = np.flatnonzero(miss <= radius)
    if inside.size == 0:
        return None
    first = inside[0]
    # The pass: consecutive segments from the first one inside.
    run = first
    while run + 1 < len(segs) and segs[run + 1] == segs[run] + 1 and miss[run + 1] <= radius:
        run += 1
    j = first + int(np.argmin(miss[first : run + 1]))
    k = int(segs[j])
    cum = path.cumulative
    return float(cum[k] + t[j] * (cum[k + 1] - cum[k])), float(miss[j])


def closest_approach(
    path: FlightPath, point: np.ndarray, radius: float, *, compiled: bool = False
) -> tuple[float, float]:
    """(distance flown, 3D miss) where the path first passes within ``radius`` of ``point``,
    at the closest approach of that pass; else at its closest approach overall. ``compiled``:
    the same in sim/flight_kernel.py (a flown track has tens of thousands of segments)."""
    point = np.asarray(point, float)
    if len(path.points) < 2:
        return 0.0, float(np.linalg.norm(path.points[0] - point))
    if compiled:
        points = path.contiguous_points
        d, miss = flight_kernel.closest_approach(
            points, path.cumulative, point, float(radius), path.blocks
        )
        return float(d), float(miss)
    segs = np.arange(len(path.points) - 1)
    hit = _first_pass(path, point, segs, radius)
    if hit is not None:
        return hit
    miss, t = _segment_distances(path, point, segs)
    j = int(np.argmin(miss))
    cum = path.cumulative
    return float(cum[j] + t[j] * (cum[j + 1] - cum[j])), float(miss[j])


def find_encounters(
    path: FlightPath, scenario: Scenario, capture_radius: float = DEFAULT_CAPTURE_RADIUS_M
) -> list[Encounter]:
    """Correction points the path passes within ``capture_radius`` (3D) of, in flight order,
    each at the closest approach of its first pass (a landmark is used at most once)."""
    mask = (scenario.kind == Kind.V) | (scenario.kind == Kind.H)
    idx = np.flatnonzero(mask)
    if len(path.points) < 2 or idx.size == 0:
        return []
    seg_len = np.linalg.norm(np.diff(path.points, axis=0), axis=1)
    # A landmark within the radius of a segment is within radius + half its length of one of
    # the segment's ends.
    tree = cKDTree(path.points)
    reach = capture_radius + float(seg_len.max()) / 2 + 1e-6
    near = tree.query_ball_point(scenario.xyz[idx], r=reach)
    last = len(path.points) - 2
    out: list[Encounter] = []
    for j, pts in enumerate(near):
        if not pts:
            continue
        pts_arr = np.asarray(pts)
        segs = np.unique(np.clip(np.concatenate([pts_arr - 1, pts_arr]), 0, last))
        li = int(idx[j])
        hit = _first_pass(path, scenario.xyz[li], segs, capture_radius)
        if hit is None:
            continue
        distance, miss = hit
        k = min(int(np.searchsorted(path.cumulative, distance, side="right")), len(path.seqs) - 1)
        out.append(
            Encounter(
                li,
                scenario.ids[li],
                Kind(int(scenario.kind[li])),
                bool(scenario.unreliable[li]),
                distance,
                miss,
                int(path.seqs[k]),
            )
        )
    out.sort(key=lambda e: e.distance)
    return out


def _fly(
    path: FlightPath,
    encounters: Sequence[Encounter],
    scenario: Scenario,
    params: Parameters,
    rng: np.random.Generator,
    capture_radius: float,
) -> ReplayRun:
    delta = params.delta
    residual_m = params.residual_m
    v = h = 0.0  # metres flown since the last reset of each component
    last = 0.0
    rows: list[CorrectionRow] = []
    for e in encounters:
        v += e.distance - last
        h += e.distance - last
        last = e.distance
        v_lim_m, h_lim_m = params.limits_m(e.kind)
        v_lim, h_lim = params.limits(e.kind)
        ok = v <= v_lim_m and h <= h_lim_m
        succeeded: bool | None = None
        v_before, h_before = v, h
        if ok:
            succeeded = (not e.unreliable) or bool(rng.random() < params.p_success)
            if e.kind == Kind.V:
                v = 0.0 if succeeded else min(v, residual_m)
            else:
                h = 0.0 if succeeded else min(h, residual_m)
        rows.append(
            CorrectionRow(
                e.id,
                e.kind.name,
                e.seq,
                e.distance,
                e.unreliable,
                v_before * delta,
                h_before * delta,
                v_lim,
                h_lim,
                v_lim - v_before * delta,
                h_lim - h_before * delta,
                ok,
                succeeded,
                v * delta,
                h * delta,
                miss=e.miss,
            )
        )
        if not ok:
            what = "vertical" if v_before > v_lim_m else "horizontal"
            return ReplayRun(
                False,
                True,
                f"lost at {e.kind.name} point {e.id}: {what} error over its limit on arrival",
                e.distance,
                tuple(rows),
                v * delta,
                h * delta,
                False,
                math.inf,
            )
    total = path.length
    v += total - last
    h += total - last
    return _arrival_at_b(path, scenario, params, capture_radius, total, tuple(rows), v, h)


def _arrival_at_b(
    path: FlightPath,
    scenario: Scenario,
    params: Parameters,
    capture: float,
    flown: float,
    rows: tuple[CorrectionRow, ...],
    v: float,
    h: float,
) -> ReplayRun:
    """The run's end at B: ``path`` ends at its closest approach, which must be within the
    capture radius of B with both errors (``v``, ``h``: metres flown's worth) within theta. One
    rule for the still-air replay (``_fly``) and the flight on the estimate (``_ins_run``)."""
    miss_b = float(np.linalg.norm(path.points[-1] - scenario.xyz[scenario.end]))
    reached = miss_b <= capture
    theta_m = params.limits_m(Kind.B)[0]
    within = v <= theta_m and h <= theta_m
    reason = ""
    if not reached:
        reason = (
            f"the flight passes {miss_b:.1f} m from B at its closest (3D), outside the capture "
            f"radius {capture:g} m"
        )
    elif not within:
        reason = "lost at B: an error over theta on arrival"
    delta = params.delta
    return ReplayRun(reached and within, reached and not within, reason, flown, rows,
                     v * delta, h * delta, reached, miss_b)  # fmt: skip


def monte_carlo(
    path: FlightPath,
    encounters: Sequence[Encounter],
    scenario: Scenario,
    params: Parameters,
    runs: int,
    seed: int,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    confidence: float = 0.99,
) -> MonteCarloSummary:
    """``runs`` replays at once (numpy over runs), with a Wilson interval at ``confidence``."""
    if runs < 1:
        raise ValueError("runs must be >= 1")
    rng = np.random.default_rng(seed)
    residual_m = params.residual_m
    v = np.zeros(runs)
    h = np.zeros(runs)
    ok = np.ones(runs, dtype=bool)
    failed = np.zeros(runs, dtype=bool)  # a failed correction before the run was lost
    failed_ids: list[list[str]] = [[] for _ in range(runs)]
    reasons = [""] * runs  # where each run was lost, in the words of _fly
    last = 0.0
    for e in encounters:
        v += e.distance - last
        h += e.distance - last
        last = e.distance
        v_lim, h_lim = params.limits_m(e.kind)
        within = (v <= v_lim) & (h <= h_lim)
        for r in np.flatnonzero(ok & ~within):
            what = "vertical" if v[r] > v_lim else "horizontal"
            reasons[r] = (
                f"lost at {e.kind.name} point {e.id}: {what} error over its limit on arrival"
            )
        ok &= within
        won = rng.random(runs) < params.p_success if e.unreliable else np.ones(runs, bool)
        failed |= ok & ~won
        for r in np.flatnonzero(ok & ~won):
            failed_ids[r].append(e.id)
        if e.kind == Kind.V:
            v = np.where(won, 0.0, np.minimum(v, residual_m))
        else:
            h = np.where(won, 0.0, np.minimum(h, residual_m))
    v += path.length - last
    h += path.length - last
    theta_m = params.limits_m(Kind.B)[0]
    miss_b = float(np.linalg.norm(path.points[-1] - scenario.xyz[scenario.end]))
    reached = miss_b <= capture_radius
    arrived = (v <= theta_m) & (h <= theta_m) & reached
    for r in np.flatnonzero(ok & ~arrived):
        reasons[r] = (
            "lost at B: an error over theta on arrival"
            if reached
            else f"the flight passes {miss_b:.1f} m from B at its closest (3D), outside the "
            f"capture radius {capture_radius:g} m"
        )
    ok &= arrived
    successes = int(np.count_nonzero(ok))
    low, high = wilson_interval(successes, runs, confidence)
    flight = int(np.count_nonzero(~ok & ~failed))
    lost = tuple(
        LostRun(False, tuple(failed_ids[r]), int(r), reasons[r]) for r in np.flatnonzero(~ok)
    )
    return MonteCarloSummary(
        runs, successes, successes / runs, low, high, confidence, flight,
        runs - successes - flight, lost_runs=lost,
    )  # fmt: skip


def mission_landmarks(
    nominal: FlightPath, scenario: Scenario, capture_radius: float = DEFAULT_CAPTURE_RADIUS_M
) -> list[tuple[int, int]]:
    """(landmark, seq) of the correction landmarks the mission has a waypoint on (within
    ``capture_radius``), in mission order, each once."""
    mask = (scenario.kind == Kind.V) | (scenario.kind == Kind.H)
    idx = np.flatnonzero(mask)
    if idx.size == 0 or len(nominal.points) < 2:
        return []
    tree = cKDTree(scenario.xyz[idx])
    out: list[tuple[int, int]] = []
    seen: set[int] = set()
    for p, seq in zip(nominal.points[1:], nominal.seqs[1:], strict=True):
        for j in tree.query_ball_point(p, r=capture_radius):
            li = int(idx[j])
            if li not in seen:
                seen.add(li)
                out.append((li, int(seq)))
    return out


def find_missed(
    nominal: FlightPath,
    flown: FlightPath,
    encounters: Sequence[Encounter],
    scenario: Scenario,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    *,
    compiled: bool = False,
    landmarks: Sequence[tuple[int, int]] | None = None,
) -> list[Missed]:
    """Correction landmarks the mission has a waypoint on (within ``capture_radius``) that the
    flown track did not pass within ``capture_radius`` of, in mission order (``compiled``:
    their closest approaches found by the kernel). ``landmarks``: mission_landmarks of
    ``nominal``, when the caller has them (a Monte Carlo flies one mission many times)."""
    if landmarks is None:
        landmarks = mission_landmarks(nominal, scenario, capture_radius)
    met = {e.landmark for e in encounters}
    out: list[Missed] = []
    for li, seq in landmarks:
        if li in met:
            continue
        distance, miss = closest_approach(
            flown, scenario.xyz[li], capture_radius, compiled=compiled
        )
        kind = Kind(int(scenario.kind[li])).name
        out.append(Missed(li, scenario.ids[li], kind, seq, distance, miss))
    return out


def flown_path(flight: guidance.Flight) -> FlightPath:
    """The flown track as a path (one point per step of the flight model)."""
    # Contiguous: the compiled closest approaches read it many times.
    points = np.ascontiguousarray(flight.xyz, dtype=float)
    return FlightPath(points, tuple(flight.current.tolist()), tuple(flight.airspeed.tolist()))


def _ins_run(
    ins: InsEstimate, path: FlightPath, scenario: Scenario, params: Parameters, capture: float
) -> tuple[ReplayRun, list[Encounter]]:
    """The run the INS made in flight, up to ``path``'s end: the closest approach to B, or where
    the flight was lost before it came to B."""
    delta = params.delta
    end = path.length
    rows: list[CorrectionRow] = []
    encounters: list[Encounter] = []
    v = h = end  # no correction: the errors at B are the metres flown
    last_d, v_after, h_after = 0.0, 0.0, 0.0
    cum = path.cumulative
    for c in sorted(ins.corrections, key=lambda c: c.distance):
        if c.distance > end + 1e-6:
            break
        v_lim, h_lim = params.limits(c.kind)
        k = min(int(np.searchsorted(cum, c.distance, side="right")), len(path.seqs) - 1)
        seq = int(path.seqs[k])
        encounters.append(
            Encounter(c.landmark, c.id, c.kind, c.unreliable, c.distance, c.miss, seq)
        )
        rows.append(
            CorrectionRow(
                c.id, c.kind.name, seq, c.distance, c.unreliable,
                c.v_before_m * delta, c.h_before_m * delta, v_lim, h_lim,
                v_lim - c.v_before_m * delta, h_lim - c.h_before_m * delta, c.within_limits,
                c.succeeded, c.v_after_m * delta, c.h_after_m * delta, c.miss,
                c.estimate_error_m,
            )
        )  # fmt: skip
        if not c.within_limits:
            what = "vertical" if c.v_before_m > params.limits_m(c.kind)[0] else "horizontal"
            reason = f"lost at {c.kind.name} point {c.id}: {what} error over its limit on arrival"
            run = ReplayRun(False, True, reason, c.distance, tuple(rows), c.v_after_m * delta,
                            c.h_after_m * delta, False, math.inf)  # fmt: skip
            return run, encounters
        last_d, v_after, h_after = c.distance, c.v_after_m, c.h_after_m
    if rows:
        v, h = v_after + (end - last_d), h_after + (end - last_d)
    return _arrival_at_b(path, scenario, params, capture, end, tuple(rows), v, h), encounters


@dataclass(frozen=True)
class FlightSetup:
    """What every flight of one replay shares: the vehicle's stored items, where and how it
    flies them."""

    items: tuple[MissionItem, ...]
    scenario: Scenario
    params: Parameters
    profile: VehicleProfile
    flavour: str
    autopilot: guidance.AutopilotParams
    frame: LocalFrame
    home_at_seq0: bool
    home_alt: float | None
    course: float | None
    capture_radius: float
    dt: float
    navigate_on_estimate: bool
    error_unit: float
    nominal: FlightPath
    compiled: bool = True  # plain steps in sim/flight_kernel.py; False: the Python reference
    # Another flight model than the point mass (sim/jsbsim_airframe.py FlightModel), or None.
    flight_model: object | None = None

    @cached_property
    def mission_landmarks(self) -> list[tuple[int, int]]:
        return mission_landmarks(self.nominal, self.scenario, self.capture_radius)

    @cached_property
    def commands(self) -> list[guidance.NavCommand]:
        """The stored items as the navigators' commands (the same for every flight)."""
        return guidance.mission_commands(
            self.items, self.frame, self.scenario_start, home_at_seq0=self.home_at_seq0,
            home_alt=self.home_alt,
        )  # fmt: skip

    @property
    def scenario_start(self) -> tuple[float, float, float]:
        a = np.asarray(self.scenario.xyz[self.scenario.start], float)
        return (float(a[0]), float(a[1]), float(a[2]))

    def fly_once(
        self, rng: np.random.Generator, wind: WindModel | None
    ) -> tuple[ReplayRun, guidance.Flight, FlightPath, list[Encounter], list[Missed]]:
        """One flight: in ``wind``, on the INS estimate (directions and outcomes from ``rng``)
        when navigating on the estimate; else the truth is flown and the INS replayed after."""
        sc = self.scenario
        a = np.asarray(sc.xyz[sc.start], float)
        ins = None
        if self.navigate_on_estimate:
            ins = InsEstimate(sc, self.params, rng, capture_radius=self.capture_radius,
                              error_unit=self.error_unit)  # fmt: skip
        flight = guidance.fly(
            self.items, self.frame, (float(a[0]), float(a[1]), float(a[2])), self.profile,
            flavour=self.flavour, params=self.autopilot, home_at_seq0=self.home_at_seq0,
            home_alt=self.home_alt, course=self.course, dt=self.dt, wind=wind, ins=ins,
            compiled=self.compiled, commands=self.commands,
            flight_model=self.flight_model,  # type: ignore[arg-type]
        )  # fmt: skip
        track = flown_path(flight)
        b_distance, b_miss = closest_approach(
            track, sc.xyz[sc.end], self.capture_radius, compiled=self.compiled
        )
        if flight.ended == "lost" and b_miss > self.capture_radius:
            # Lost on arrival at a landmark before it came to B: the run is the flight up to
            # its loss. Its closest approach to B so far can lie kilometres back (a route that
            # turns away from B), and cutting there would drop the corrections after it (the
            # failed one and the loss) and call the landmarks met after it missed: a loss by
            # chance at unreliable points counted as lost by the flight.
            path = track
        else:
            path = track.until(b_distance)
        if ins is not None:
            ins.finish()
            run, encounters = _ins_run(ins, path, sc, self.params, self.capture_radius)
        else:
            encounters = find_encounters(path, sc, self.capture_radius)
            run = _fly(path, encounters, sc, self.params, rng, self.capture_radius)
        missed = find_missed(
            self.nominal, path, encounters, sc, self.capture_radius, compiled=self.compiled,
            landmarks=self.mission_landmarks,
        )  # fmt: skip
        if flight.ended == "lost":
            # The flight ended where it was lost: a landmark whose mission item it had not
            # reached yet was not missed, just not reached.
            done = max((e.seq for e in flight.events if e.kind == "reached"), default=-1)
            missed = [m for m in missed if m.seq <= done]
        if any(m.distance <= run.flown_length for m in missed):
            run = replace(run, missed_before_loss=True)
        return run, flight, path, encounters, missed


def monte_carlo_flights(
    setup: FlightSetup, wind: WindSpec, runs: int, seed: int, confidence: float = 0.99
) -> MonteCarloSummary:
    """``runs`` flights, each with its own draws from (``seed``, run): the wind's direction
    (when not given) and gusts, the INS error directions, the outcomes at unreliable points."""
    if runs < 1:
        raise ValueError("runs must be >= 1")
    successes = flight_losses = 0
    lost: list[LostRun] = []
    for k in range(runs):
        rng = np.random.default_rng([seed, k])
        model = None if wind.still else wind.draw(rng)
        run, _, _, _, missed = setup.fly_once(rng, model)
        successes += run.arrived
        flight_losses += run.flight_lost
        if not run.arrived:
            failed = tuple(c.id for c in run.corrections if c.succeeded is False)
            before = tuple(m.id for m in missed if m.distance <= run.flown_length)
            lost.append(LostRun(run.missed_before_loss, failed, k, run.lost_reason, before))
    low, high = wilson_interval(successes, runs, confidence)
    return MonteCarloSummary(
        runs, successes, successes / runs, low, high, confidence, flight_losses,
        runs - successes - flight_losses, flown=True, lost_runs=tuple(lost),
    )  # fmt: skip


def replay(
    items: Sequence[MissionItem],
    scenario: Scenario,
    params: Parameters | None = None,
    *,
    seed: int = 0,
    runs: int = 0,
    home_at_seq0: bool = False,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    cruise_speed: float | None = None,
    home_alt: float | None = None,
    confidence: float = 0.99,
    flavour: str | None = None,
    profile: VehicleProfile | None = None,
    autopilot: guidance.AutopilotParams | None = None,
    dt: float = guidance.DEFAULT_STEP_S,
    wind: WindSpec | None = None,
    navigate_on_estimate: bool = False,
    error_unit: float = DEFAULT_ERROR_UNIT_M,
    compiled: bool = True,
    flight_model: object | None = None,
) -> ReplayReport:
    """Fly the stored ``items`` and replay the INS against the landmark database ``scenario``.

    ``params`` default to the scenario's, ``profile`` (the aircraft) to ``scenario.vehicle``,
    with ``cruise_speed`` (the autopilot's cruise parameter) for its airspeed when given.
    ``flavour`` defaults to ArduPilot when ``home_at_seq0`` else PX4; ``autopilot`` to its
    shipped limits with the profile's turning radius as loiter radius. ``wind`` (default still
    air) is drawn from ``seed`` for the one replay reported. With ``navigate_on_estimate`` the
    aircraft steers its INS estimate (sim/ins.py, ``error_unit`` metres per error unit) and
    corrections happen in flight, in the truth; otherwise it flies the truth and the INS is
    replayed along the track.

    With ``runs`` > 0 a Monte Carlo of that many replays (seeded from ``seed`` too): when every
    flight is the same (still air, the truth flown) the outcomes at unreliable points are drawn
    over the one flight; otherwise each run is flown on its own with its own draws.

    ``compiled`` flies the flight's plain steps in the numba kernel (sim/flight_kernel.py);
    False flies all of them in the Python navigators, the reference the kernel is tested on.
    ``flight_model`` (sim/jsbsim_airframe.py ``FlightModel``) flies JSBSim instead of the point
    mass (as deterministic: a still-air flight on the truth is flown once for every run).
    """
    # The aircraft is held to the true limits: the planner's reserve is its own margin.
    params = (params or scenario.params).flown()
    profile = profile or scenario.vehicle
    if cruise_speed is not None and cruise_speed > 0:
        profile = replace(profile, cruise_airspeed=float(cruise_speed))
    flavour = flavour or ("ardupilot" if home_at_seq0 else "px4")
    wind = wind or WindSpec()
    frame = scenario_frame(scenario)
    nominal = decode_path(
        items,
        scenario,
        home_at_seq0=home_at_seq0,
        home_alt=home_alt,
        cruise_speed=profile.cruise_airspeed,
        capture_radius=capture_radius,
        frame=frame,
    )
    course = None
    if scenario.heading_at_a is not None:
        hx, hy, _ = scenario.heading_at_a
        if math.hypot(hx, hy) > 0:
            course = math.atan2(hy, hx)
    setup = FlightSetup(
        tuple(items), scenario, params, profile, flavour,
        autopilot or guidance.AutopilotParams(flavour, loiter_radius=profile.turn_radius),
        frame, home_at_seq0, home_alt, course, capture_radius, dt, navigate_on_estimate,
        error_unit, nominal, compiled, flight_model,
    )  # fmt: skip
    rng = np.random.default_rng(seed)
    model = None if wind.still else wind.draw(np.random.default_rng([seed, 2**31]))
    run, flight, path, encounters, missed = setup.fly_once(rng, model)
    track = flown_path(flight)
    k = min(int(np.searchsorted(track.cumulative, path.length, side="right")), len(flight.t) - 1)
    mc = None
    if runs > 0:
        if wind.still and not navigate_on_estimate:
            mc = monte_carlo(
                path, encounters, scenario, params, runs, seed + 1, capture_radius, confidence
            )
            if missed:  # one flight for every run: a landmark it missed loses them all
                lost = runs - mc.successes
                mc = replace(
                    mc, flight_losses=lost, correction_losses=0,
                    lost_runs=tuple(
                        replace(r, missed=True, missed_ids=tuple(m.id for m in missed))
                        for r in mc.lost_runs
                    ),
                )  # fmt: skip
        else:
            mc = monte_carlo_flights(setup, wind, runs, seed + 1, confidence)
    return ReplayReport(
        run=run,
        mission_length=nominal.length,
        waypoints=len(nominal.points) - 1,
        flight_time_s=float(flight.t[k]),
        capture_radius=capture_radius,
        theta=params.theta,
        monte_carlo=mc,
        encounters=tuple(encounters),
        flight=flight,
        nominal=nominal,
        flown=path,
        missed=tuple(missed),
    )
