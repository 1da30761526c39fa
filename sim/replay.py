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

The parts live by purpose: the report's records in sim/replay_records.py, the mission's path in
sim/mission_path.py, where a path meets the landmarks in sim/encounters.py, the error budget
along a path in sim/correction_runs.py, the flights and their Monte Carlo in
sim/replay_flights.py; every name stays importable from here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from gcs_planner.sim import guidance
from gcs_planner.sim.correction_runs import arrival_at_b, corrections_run, ins_run, monte_carlo
from gcs_planner.sim.encounters import (
    _first_pass,
    _segment_distances,
    closest_approach,
    find_encounters,
    find_missed,
    mission_landmarks,
)
from gcs_planner.sim.ins import DEFAULT_ERROR_UNIT_M
from gcs_planner.sim.mission_path import (
    CHORD_SHORTFALL,
    DEFAULT_CRUISE_SPEED,
    DENSIFY_MAX_DEG,
    MAV_CMD_DO_CHANGE_SPEED,
    QUANTISATION_M,
    decode_path,
    flown_path,
    scenario_frame,
)
from gcs_planner.sim.replay_flights import FlightSetup, monte_carlo_flights
from gcs_planner.sim.replay_records import (
    CorrectionRow,
    Encounter,
    FlightPath,
    LostRun,
    Missed,
    MonteCarloSummary,
    ReplayReport,
    ReplayRun,
)
from gcs_planner.sim.wind import WindSpec

from gcs_planner.aircraft.autopilot import AUTOPILOTS, DEFAULT_AUTOPILOT
from gcs_planner.aircraft.profile import DEFAULT_CAPTURE_RADIUS_M, VehicleProfile
from gcs_planner.mission.items import MissionItem
from gcs_planner.scenario.georef import DEFAULT_ORIGIN
from gcs_planner.scenario.model import Parameters, Scenario

# The names the replay's callers have always imported from here, wherever they now live.
_fly = corrections_run
_ins_run = ins_run
_arrival_at_b = arrival_at_b

__all__ = [
    "CHORD_SHORTFALL",
    "DEFAULT_CAPTURE_RADIUS_M",
    "DEFAULT_CRUISE_SPEED",
    "DEFAULT_ORIGIN",
    "DENSIFY_MAX_DEG",
    "MAV_CMD_DO_CHANGE_SPEED",
    "QUANTISATION_M",
    "CorrectionRow",
    "Encounter",
    "FlightPath",
    "FlightSetup",
    "LostRun",
    "Missed",
    "MonteCarloSummary",
    "ReplayReport",
    "ReplayRun",
    "_arrival_at_b",
    "_first_pass",
    "_fly",
    "_ins_run",
    "_segment_distances",
    "closest_approach",
    "decode_path",
    "find_encounters",
    "find_missed",
    "flavour_for",
    "flown_path",
    "mission_landmarks",
    "monte_carlo",
    "monte_carlo_flights",
    "replay",
    "scenario_frame",
]


def flavour_for(home_at_seq0: bool) -> str:
    """The autopilot whose missions keep (or not) home as item 0, as ``home_at_seq0`` says: the
    first record with that trait, else the default autopilot."""
    return next(
        (ap.firmware for ap in AUTOPILOTS.values() if ap.home_at_seq0 == home_at_seq0),
        DEFAULT_AUTOPILOT,
    )


def _course_at_a(scenario: Scenario) -> float | None:
    """The course (rad, atan2(north, east)) the aircraft starts on at A; None when the scenario
    gives no horizontal heading there."""
    if scenario.heading_at_a is None:
        return None
    hx, hy, _ = scenario.heading_at_a
    if math.hypot(hx, hy) > 0:
        return math.atan2(hy, hx)
    return None


def _monte_carlo(
    setup: FlightSetup,
    wind: WindSpec,
    path: FlightPath,
    encounters: Sequence[Encounter],
    missed: Sequence[Missed],
    runs: int,
    seed: int,
    confidence: float,
    spent: str = "",
) -> MonteCarloSummary:
    """The Monte Carlo of ``runs`` replays: over the one flight ``path`` when every flight is
    the same (still air, the truth flown), else each run flown on its own. ``spent``: why the
    one flight was lost when its endurance ran out before B (every run is, by the flight)."""
    if not (wind.still and not setup.navigate_on_estimate):
        return monte_carlo_flights(setup, wind, runs, seed, confidence)
    mc = monte_carlo(
        path, encounters, setup.scenario, setup.params, runs, seed, setup.capture_radius,
        confidence,
    )  # fmt: skip
    if missed:  # one flight for every run: a landmark it missed loses them all
        lost = runs - mc.successes
        mc = replace(
            mc, flight_losses=lost, correction_losses=0,
            lost_runs=tuple(
                replace(r, missed=True, missed_ids=tuple(m.id for m in missed))
                for r in mc.lost_runs
            ),
        )  # fmt: skip
    if spent:  # one flight for every run: out of endurance before B, every run is lost by it
        mc = replace(
            mc, flight_losses=runs - mc.successes, correction_losses=0,
            lost_runs=tuple(
                replace(r, reason=spent, out_of_endurance=True) for r in mc.lost_runs
            ),
        )  # fmt: skip
    return mc


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
    endurance: float | None = None,
) -> ReplayReport:
    """Fly the stored ``items`` and replay the INS against the landmark database ``scenario``.

    ``params`` default to the scenario's, ``profile`` (the aircraft) to ``scenario.vehicle``,
    with ``cruise_speed`` (the autopilot's cruise parameter) for its airspeed when given.
    ``flavour`` defaults to the autopilot that keeps home as item 0 when ``home_at_seq0``
    (ArduPilot), else the one that does not (PX4); ``autopilot`` to its shipped limits with the
    profile's turning radius as loiter radius. ``wind`` (default still air) is drawn from
    ``seed`` for the one replay reported. With ``navigate_on_estimate`` the aircraft steers its
    INS estimate (sim/ins.py, ``error_unit`` metres per error unit) and corrections happen in
    flight, in the truth; otherwise it flies the truth and the INS is replayed along the track.

    With ``runs`` > 0 a Monte Carlo of that many replays (seeded from ``seed`` too): when every
    flight is the same (still air, the truth flown) the outcomes at unreliable points are drawn
    over the one flight; otherwise each run is flown on its own with its own draws.

    ``compiled`` flies the flight's plain steps in the numba kernel (sim/flight_kernel.py);
    False flies all of them in the Python navigators, the reference the kernel is tested on.
    ``flight_model`` (sim/jsbsim_airframe.py ``FlightModel``) flies JSBSim instead of the point
    mass (as deterministic: a still-air flight on the truth is flown once for every run).
    ``endurance`` (s from A): past it the aircraft's low-battery failsafe ends the mission; a
    flight that has not come to B by then is lost, by the flight.
    """
    # The aircraft is held to the true limits: the planner's reserve is its own margin.
    params = (params or scenario.params).flown()
    profile = profile or scenario.vehicle
    if cruise_speed is not None and cruise_speed > 0:
        profile = replace(profile, cruise_airspeed=float(cruise_speed))
    flavour = flavour or flavour_for(home_at_seq0)
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
    setup = FlightSetup(
        tuple(items), scenario, params, profile, flavour,
        autopilot or guidance.AutopilotParams(flavour, loiter_radius=profile.turn_radius),
        frame, home_at_seq0, home_alt, _course_at_a(scenario), capture_radius, dt,
        navigate_on_estimate, error_unit, nominal, compiled, flight_model, endurance,
    )  # fmt: skip
    rng = np.random.default_rng(seed)
    model = None if wind.still else wind.draw(np.random.default_rng([seed, 2**31]))
    run, flight, path, encounters, missed = setup.fly_once(rng, model)
    track = flown_path(flight)
    k = min(int(np.searchsorted(track.cumulative, path.length, side="right")), len(flight.t) - 1)
    mc = None
    if runs > 0:
        spent = run.lost_reason if run.out_of_endurance else ""
        mc = _monte_carlo(setup, wind, path, encounters, missed, runs, seed + 1, confidence, spent)
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
