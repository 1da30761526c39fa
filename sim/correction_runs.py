"""The INS error budget judged along a path: every metre flown adds to both errors, each
correction point met resets its component (an unreliable one only with probability p), a limit
passed on arrival loses the vehicle, and B must be reached with both errors within theta. One
run with drawn outcomes (on the truth, or as the INS estimate made it in flight), or many runs
at once over one flight (``monte_carlo``)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from gcs_planner.sim.ins import InsEstimate
from gcs_planner.sim.replay_records import (
    CorrectionRow,
    Encounter,
    FlightPath,
    LostRun,
    MonteCarloSummary,
    ReplayRun,
)

from gcs_planner.aircraft.profile import DEFAULT_CAPTURE_RADIUS_M
from gcs_planner.dryrun.confidence import wilson_interval
from gcs_planner.scenario.model import Kind, Parameters, Scenario


def corrections_run(
    path: FlightPath,
    encounters: Sequence[Encounter],
    scenario: Scenario,
    params: Parameters,
    rng: np.random.Generator,
    capture_radius: float,
) -> ReplayRun:
    """The run along ``path`` flown on the truth, the INS replayed after: the ``encounters`` in
    flight order, each unreliable one's outcome drawn from ``rng``."""
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
    return arrival_at_b(path, scenario, params, capture_radius, total, tuple(rows), v, h)


def arrival_at_b(
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
    rule for the still-air replay (``corrections_run``) and the flight on the estimate
    (``ins_run``)."""
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
    reasons = [""] * runs  # where each run was lost, in the words of corrections_run
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


def ins_run(
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
    return arrival_at_b(path, scenario, params, capture, end, tuple(rows), v, h), encounters
