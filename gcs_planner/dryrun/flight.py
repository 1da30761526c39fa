"""The dry run's flight: the mission the vehicle stored, flown with its own parameters in the
world asked for (sim/replay.py), and what the flight met set against the plan.

Each correction the flight met is a :class:`DryRunRow` (the errors on arrival, the outcome, the
plan's errors there); a lost run of the Monte Carlo a :class:`LostRunRow`. A loss is the
flight's (:func:`lost_by_the_flight`) when the plan flown as planned with the same correction
outcomes arrives; the flown track's deviation from the planned path (:func:`max_deviation`) and
its overrun between two corrections of an error (:func:`stretch_overrun`) measure how far the
flight strayed from the plan.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from gcs_planner.aircraft.autopilot import effective, keeps_home_item
from gcs_planner.aircraft.envelope_fit import LegShortfall, legs_outside_envelope
from gcs_planner.core.probability import outcomes
from gcs_planner.core.route import Route
from gcs_planner.dryrun.world import DryRunSettings, DryRunWorld
from gcs_planner.link.vehicle_check import Shortfall, shortfalls
from gcs_planner.mission.vehicle_setup import ParameterNeed
from gcs_planner.scenario.model import Parameters
from gcs_planner.sim import replay as replay_mod
from gcs_planner.sim.guidance import NOT_FLOWN, AutopilotParams
from gcs_planner.sim.vehicle import MockVehicle

# The planned path's sampling for the deviation (the figure is within half of it).
DEVIATION_STEP_M = 2.0


@dataclass(frozen=True)
class DryRunRow:
    """One correction the vehicle met: the errors on arrival (before it) and what it did."""

    point: str
    kind: str
    unreliable: bool
    distance: float  # flown from A, metres
    v_before: float
    h_before: float
    v_limit: float
    h_limit: float
    v_margin: float
    h_margin: float
    # "ok", "failed" (unreliable point, residual kept), "lost" (over a limit) or "missed" (the
    # flight did not pass within the capture radius: no correction)
    outcome: str
    on_route: bool  # False: a landmark the path passed within the capture radius of by chance
    planned_v: float | None  # the plan's errors on arrival at this point, when it is on the route
    planned_h: float | None
    miss: float = 0.0  # 3D closest approach of the flight to the landmark, metres
    estimate_error: float = 0.0  # the INS estimate's distance from the truth there, metres


@dataclass(frozen=True)
class LostRunRow:
    """One run of the Monte Carlo that did not arrive."""

    run: int  # its index (its draws: --seed + 1 and this index)
    reason: str  # where it was lost and why
    missed: tuple[str, ...]  # landmarks of the mission it missed before its loss
    failed: tuple[str, ...]  # unreliable points whose correction failed before its loss
    by_the_flight: bool  # lost by the flight (``lost_by_the_flight``), not by chance
    out_of_endurance: bool = False  # its endurance ran out before B (by the flight)


@dataclass(frozen=True)
class Flight:
    """The stored mission flown: the replay, the autopilot as the vehicle held its parameters,
    what those parameters fell short of the plan's setup, and the plan's legs that do not fit
    its aircraft's envelope in the wind flown (``flown_wind`` m/s)."""

    replayed: replay_mod.ReplayReport
    autopilot: AutopilotParams
    setup_shortfalls: tuple[Shortfall, ...]
    envelope_shortfalls: tuple[LegShortfall, ...]
    flown_wind: float


def fly_stored_mission(
    vehicle: MockVehicle,
    world: DryRunWorld,
    settings: DryRunSettings,
    plan_dict: dict,
    wanted: Sequence[ParameterNeed],
) -> Flight:
    """Fly the mission ``vehicle`` stored, with the parameters it holds, in ``world``; first
    check what those parameters fall short of the plan's setup ``wanted`` and which legs do not
    fit the plan's envelope in the wind flown. (The mock vehicle's own replay() knows no wind
    nor INS navigation: the world's options are given here.)"""
    flavour = world.flavour
    held = vehicle.parameters
    autopilot = AutopilotParams.from_parameters(flavour, held)
    short = shortfalls(plan_dict, flavour, lambda name: held.get(name, math.nan), wanted)
    # Before the flight: the plan's legs against its aircraft's envelope in the wind flown,
    # with the flown autopilot's settle distance as the vehicle holds its parameters.
    flown_wind = world.air.speed
    settle = effective(flavour, vehicle.parameters).settle_distance
    envelope_shortfalls = legs_outside_envelope(
        world.plan.scenario, world.plan.route.points, flown_wind, settle, world.air.from_deg
    )
    replayed = replay_mod.replay(
        vehicle.mission,
        world.landmarks,
        seed=settings.seed,
        runs=settings.runs,
        home_at_seq0=keeps_home_item(flavour),
        capture_radius=world.capture_radius,
        cruise_speed=vehicle.cruise_speed,
        flavour=flavour,
        autopilot=autopilot,
        wind=world.wind,
        navigate_on_estimate=world.navigate_on_estimate,
        error_unit=world.error_unit,
        flight_model=world.flight_model,
        endurance=None if world.endurance is None else world.endurance * 60.0,
    )
    return Flight(replayed, autopilot, tuple(short), tuple(envelope_shortfalls), flown_wind)


def never_started(replayed: replay_mod.ReplayReport) -> bool:
    """Whether the flight was refused before it started: the airframe cannot fly the mission
    (sim/guidance.py ``fly``: a leg beyond its ceiling, climb or bank, or no trim at A)."""
    return replayed.flight is not None and replayed.flight.ended == NOT_FLOWN


def rows_of(replayed: replay_mod.ReplayReport, route: Route) -> list[DryRunRow]:
    """Every correction the flight made, failed or was lost at, and every landmark of the
    mission it missed on the way, in the order flown; none when the flight never started (the
    airframe cannot fly the mission: nothing was met or missed)."""
    if never_started(replayed):
        return []
    planned = {s.id: s for s in route.stops[1:-1]}
    misses = {e.id: e.miss for e in replayed.encounters}
    rows = [_row(c, planned, misses.get(c.id, 0.0)) for c in replayed.run.corrections]
    end = replayed.flown_length
    rows += [_missed_row(m, planned) for m in replayed.missed if m.distance <= end]
    rows.sort(key=lambda r: r.distance)
    return rows


def lost_runs_of(
    replayed: replay_mod.ReplayReport, route: Route, params: Parameters
) -> tuple[LostRunRow, ...]:
    """The Monte Carlo's lost runs, each said to be lost by the flight or by chance; none when
    the flight never started (nothing was flown to be lost)."""
    mc = replayed.monte_carlo
    if mc is None or never_started(replayed):
        return ()
    return tuple(
        LostRunRow(r.run, r.reason, r.missed_ids, r.failed,
                   r.out_of_endurance or lost_by_the_flight(route, params, r.missed, r.failed),
                   r.out_of_endurance)
        for r in mc.lost_runs
    )  # fmt: skip


def seeded_flight_lost(replayed: replay_mod.ReplayReport, route: Route, params: Parameters) -> bool:
    """Whether the seeded flight was lost, and by the flight."""
    run = replayed.run
    failed = [c.id for c in run.corrections if c.succeeded is False]
    if run.out_of_endurance:
        return True
    return not run.arrived and lost_by_the_flight(route, params, run.missed_before_loss, failed)


def lost_by_the_flight(
    route: Route, params: Parameters, missed: bool, failed: Collection[str]
) -> bool:
    """Whether a lost run was lost by the flight rather than by chance: it missed a landmark of
    its mission, or the plan, flown as planned (its legs' lengths, the aircraft's true limits:
    no reserve) with the same correction outcomes (those at ``failed`` failing, every other
    succeeding), arrives. A route certain to arrive is never lost by its corrections."""
    if missed:
        return True
    limits = params.flown()
    v = h = 0.0
    for stop in route.stops[1:]:
        assert stop.leg is not None
        v += stop.leg.length
        h += stop.leg.length
        v_lim, h_lim = limits.limits_m(stop.kind)
        if v > v_lim or h > h_lim:
            return False  # the plan itself is lost with these outcomes
        success, failure = outcomes(v, h, stop.kind, limits.residual_m)
        v, h = failure if (stop.unreliable and stop.id in failed) else success
    return True


def as_planned(met: list[str], planned: list[str], replayed: replay_mod.ReplayReport) -> bool:
    """The flight met the planned points in the planned order and no other, as far as it went:
    all of them, or up to the one where it was lost on arrival (a flight on the INS estimate
    ends there: what comes after depends on the draw)."""
    if met == planned:
        return True
    lost_at_point = replayed.run.lost and not replayed.run.reached_b and not replayed.missed
    return lost_at_point and bool(met) and met == planned[: len(met)]


def stretch_overrun(
    route: Route, rows: list[DryRunRow], flown_to_b: float | None = None
) -> float | None:
    """The most metres the flight flew beyond the plan between a reset of an error and a check
    of it: over every planned point the flight met, the flown stretch since the last planned
    correction of each error (or since A) less the planned one. Geometry only: what the drawn
    outcomes did does not enter, so it is what the plan's reserve has to cover."""
    flown_at = {r.point: r.distance for r in rows if r.on_route and r.outcome != "missed"}
    if flown_to_b is not None:
        flown_at[route.stops[-1].id] = flown_to_b
    worst: float | None = None
    last = {"V": (0.0, 0.0), "H": (0.0, 0.0)}  # (planned, flown) metres at the last reset
    for stop in route.stops[1:]:
        flown = flown_at.get(stop.id)
        if flown is None:
            break  # missed or never reached: the stretches after it were not flown as planned
        for planned0, flown0 in last.values():
            over = (flown - flown0) - (stop.cumulative - planned0)
            worst = over if worst is None else max(worst, over)
        if stop.kind.name in last:
            last[stop.kind.name] = (stop.cumulative, flown)
    return worst


def max_deviation(report: replay_mod.ReplayReport, planned: np.ndarray) -> tuple[float, float]:
    """(largest 3D distance of the flown track to B from the ``planned`` path, where: flown from
    A). The planned path is a polyline sampled at most ``DEVIATION_STEP_M`` apart, so the figure
    is within half that of the exact one."""
    if report.flown is None or len(planned) == 0:
        return 0.0, 0.0
    dist, _ = cKDTree(planned).query(report.flown.points)
    k = int(np.argmax(dist))
    return float(dist[k]), float(report.flown.cumulative[k])


def _missed_row(m: replay_mod.Missed, planned: dict) -> DryRunRow:
    stop = planned.get(m.id)
    nan = float("nan")
    return DryRunRow(
        point=m.id,
        kind=m.kind,
        unreliable=False,
        distance=m.distance,
        v_before=nan,
        h_before=nan,
        v_limit=nan,
        h_limit=nan,
        v_margin=nan,
        h_margin=nan,
        outcome="missed",
        on_route=stop is not None,
        planned_v=None if stop is None else stop.v_arrival,
        planned_h=None if stop is None else stop.h_arrival,
        miss=m.miss,
    )


def _row(c: replay_mod.CorrectionRow, planned: dict, miss: float = 0.0) -> DryRunRow:
    if c.succeeded is None:
        outcome = "lost"
    else:
        outcome = "ok" if c.succeeded else "failed"
    stop = planned.get(c.id)
    return DryRunRow(
        point=c.id,
        kind=c.kind,
        unreliable=c.unreliable,
        distance=c.distance,
        v_before=c.v_before,
        h_before=c.h_before,
        v_limit=c.v_limit,
        h_limit=c.h_limit,
        v_margin=c.v_margin,
        h_margin=c.h_margin,
        outcome=outcome,
        on_route=stop is not None,
        planned_v=None if stop is None else stop.v_arrival,
        planned_h=None if stop is None else stop.h_arrival,
        miss=miss,
        estimate_error=c.estimate_error_m,
    )
