"""The replay: the mock vehicle flies the mission it stored, with INS drift and corrections.

Inputs are what the vehicle has, never the planner's objects: the MAVLink items it stored, and its
own landmark database (a scenario loaded on its own: the correction points, A where it stands,
B where it must arrive, and the error model's parameters).

Flight model. The vehicle starts at A and flies straight segments from each navigation item's
position to the next (MAV_CMD_NAV_WAYPOINT, loiters, takeoff, land). The planner's turns are
already in the mission as arcs densified into waypoints at most 16 degrees apart, so flying the
chords is flying the turns with the turning radius to within the chord error: a chord under an
arc of angle a is shorter than the arc by the factor sin(a/2)/(a/2), at most 0.33 % for 16
degrees. Hence the tolerance, stated and tested: |flown - planned| <= 0.0033 * (arc length) plus
2 cm per waypoint for the degE7 quantisation of latitude/longitude; with straight legs the flown
length is the planned one to those 2 cm per waypoint.

Error model (MODEL.md). Every metre flown adds delta to both errors. Whenever the path passes
within ``capture_radius`` of a correction point of the database that has not been used yet, the
vehicle arrives there: the limits of that kind must hold (else the vehicle is lost), then the
point corrects its component; an unreliable point fails with probability 1 - p, and the
component becomes min(component, r). At the end of the mission the vehicle must be within
``capture_radius`` of B with both errors <= theta. Errors are kept in metres flown since the last
reset, as the planner keeps them, and compared with ``Parameters.limits_m``.

The path and the corrections it meets do not depend on chance, only the outcomes at unreliable
points do; so a Monte Carlo over N replays draws N outcome vectors over the same encounters.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from gcs_planner.confidence import wilson_interval
from gcs_planner.mission.georef import DEFAULT_ORIGIN, LocalFrame
from gcs_planner.mission.items import MissionItem
from gcs_planner.scenario.model import Kind, Parameters, Scenario
from gcs_planner.vehicle import DEFAULT_CAPTURE_RADIUS_M, DEFAULT_CRUISE_AIRSPEED

# MAV_CMD values whose x/y/z are a position the vehicle flies to.
NAV_POSITION_COMMANDS = frozenset({16, 17, 18, 19, 21, 22, 31})
MAV_CMD_DO_CHANGE_SPEED = 178
GLOBAL_AMSL_FRAMES = frozenset({0, 5})
GLOBAL_RELATIVE_FRAMES = frozenset({3, 6})

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

    @property
    def cumulative(self) -> np.ndarray:
        seg = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        return np.concatenate([[0.0], np.cumsum(seg)])

    @property
    def length(self) -> float:
        return float(self.cumulative[-1])

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


@dataclass(frozen=True)
class MonteCarloSummary:
    runs: int
    successes: int
    success_rate: float
    ci_low: float
    ci_high: float
    confidence: float


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
            "corrections": [asdict(c) for c in self.run.corrections],
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
        if item.command not in NAV_POSITION_COMMANDS:
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


def find_encounters(
    path: FlightPath, scenario: Scenario, capture_radius: float = DEFAULT_CAPTURE_RADIUS_M
) -> list[Encounter]:
    """Correction points the path passes within ``capture_radius`` of, in flight order, each
    at its first closest approach (a landmark is used at most once)."""
    mask = (scenario.kind == Kind.V) | (scenario.kind == Kind.H)
    idx = np.flatnonzero(mask)
    marks = scenario.xyz[idx]
    used = np.zeros(len(idx), dtype=bool)
    cum = path.cumulative
    out: list[Encounter] = []
    for k in range(len(path.points) - 1):
        p, q = path.points[k], path.points[k + 1]
        d = q - p
        seg_len2 = float(d @ d)
        lo = np.minimum(p, q) - capture_radius
        hi = np.maximum(p, q) + capture_radius
        near = np.flatnonzero(~used & np.all((marks >= lo) & (marks <= hi), axis=1))
        if near.size == 0:
            continue
        rel = marks[near] - p
        t = np.zeros(near.size) if seg_len2 == 0 else np.clip(rel @ d / seg_len2, 0.0, 1.0)
        miss = np.linalg.norm(rel - t[:, None] * d, axis=1)
        hit = miss <= capture_radius
        for j in np.flatnonzero(hit)[np.argsort(t[hit], kind="stable")]:
            li = int(idx[near[j]])
            used[near[j]] = True
            seq = path.seqs[k + 1] if t[j] > 0.5 else path.seqs[k]
            out.append(
                Encounter(
                    li,
                    scenario.ids[li],
                    Kind(int(scenario.kind[li])),
                    bool(scenario.unreliable[li]),
                    float(cum[k] + t[j] * math.sqrt(seg_len2)),
                    float(miss[j]),
                    int(seq),
                )
            )
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
    residual_m = params.fail_residual / delta
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
    b = scenario.xyz[scenario.end]
    miss_b = float(np.linalg.norm(path.points[-1] - b))
    reached = miss_b <= capture_radius
    theta_m = params.limits_m(Kind.B)[0]
    within = v <= theta_m and h <= theta_m
    reason = ""
    if not reached:
        reason = f"the mission ends {miss_b:.1f} m from B (capture radius {capture_radius:g} m)"
    elif not within:
        reason = "lost at B: an error over theta on arrival"
    return ReplayRun(
        reached and within,
        reached and not within,
        reason,
        total,
        tuple(rows),
        v * delta,
        h * delta,
        reached,
        miss_b,
    )


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
    residual_m = params.fail_residual / params.delta
    v = np.zeros(runs)
    h = np.zeros(runs)
    ok = np.ones(runs, dtype=bool)
    last = 0.0
    for e in encounters:
        v += e.distance - last
        h += e.distance - last
        last = e.distance
        v_lim, h_lim = params.limits_m(e.kind)
        ok &= (v <= v_lim) & (h <= h_lim)
        won = rng.random(runs) < params.p_success if e.unreliable else np.ones(runs, bool)
        if e.kind == Kind.V:
            v = np.where(won, 0.0, np.minimum(v, residual_m))
        else:
            h = np.where(won, 0.0, np.minimum(h, residual_m))
    v += path.length - last
    h += path.length - last
    theta_m = params.limits_m(Kind.B)[0]
    reached = float(np.linalg.norm(path.points[-1] - scenario.xyz[scenario.end])) <= capture_radius
    ok &= (v <= theta_m) & (h <= theta_m) & reached
    successes = int(np.count_nonzero(ok))
    low, high = wilson_interval(successes, runs, confidence)
    return MonteCarloSummary(runs, successes, successes / runs, low, high, confidence)


def replay(
    items: Sequence[MissionItem],
    scenario: Scenario,
    params: Parameters | None = None,
    *,
    seed: int = 0,
    runs: int = 0,
    home_at_seq0: bool = False,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    cruise_speed: float = DEFAULT_CRUISE_SPEED,
    home_alt: float | None = None,
    confidence: float = 0.99,
) -> ReplayReport:
    """Replay the stored ``items`` against the landmark database ``scenario``.

    ``params`` default to the scenario's. One replay is drawn with ``seed``; with ``runs`` > 0
    a Monte Carlo of that many replays (seeded from ``seed`` too) gives the success rate.
    """
    params = params or scenario.params
    path = decode_path(
        items,
        scenario,
        home_at_seq0=home_at_seq0,
        home_alt=home_alt,
        cruise_speed=cruise_speed,
        capture_radius=capture_radius,
    )
    encounters = find_encounters(path, scenario, capture_radius)
    run = _fly(path, encounters, scenario, params, np.random.default_rng(seed), capture_radius)
    seg = np.diff(path.cumulative)
    speeds = np.asarray(path.speeds[1:], float)
    flight_time = float(np.sum(seg / np.where(speeds > 0, speeds, cruise_speed)))
    mc = None
    if runs > 0:
        mc = monte_carlo(
            path, encounters, scenario, params, runs, seed + 1, capture_radius, confidence
        )
    return ReplayReport(
        run=run,
        mission_length=path.length,
        waypoints=len(path.points) - 1,
        flight_time_s=flight_time,
        capture_radius=capture_radius,
        theta=params.theta,
        monte_carlo=mc,
        encounters=tuple(encounters),
    )
