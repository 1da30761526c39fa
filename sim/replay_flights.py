"""The flights of one replay: what they share (``FlightSetup``: the stored items, the aircraft,
the autopilot, the frame), one flight with its INS run, and the Monte Carlo that flies each run
on its own with its own draws (wind, gusts, the INS estimate, the outcomes at unreliable
points)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from gcs_planner.sim import guidance
from gcs_planner.sim.correction_runs import corrections_run, ins_run
from gcs_planner.sim.encounters import (
    closest_approach,
    find_encounters,
    find_missed,
    mission_landmarks,
)
from gcs_planner.sim.ins import InsEstimate
from gcs_planner.sim.mission_path import flown_path
from gcs_planner.sim.replay_records import (
    Encounter,
    FlightPath,
    LostRun,
    Missed,
    MonteCarloSummary,
    ReplayRun,
)
from gcs_planner.sim.wind import WindModel, WindSpec

from gcs_planner.aircraft.profile import VehicleProfile
from gcs_planner.dryrun.confidence import wilson_interval
from gcs_planner.mission.items import MissionItem
from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.scenario.model import Parameters, Scenario


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
    # The aircraft's endurance (s from A), past which its low-battery failsafe ends the
    # mission (sim/guidance.py fly); None: unlimited.
    endurance: float | None = None

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
            endurance=self.endurance,
        )  # fmt: skip
        track = flown_path(flight)
        b_distance, b_miss = closest_approach(
            track, sc.xyz[sc.end], self.capture_radius, compiled=self.compiled
        )
        ended_early = flight.ended in ("lost", guidance.ENDURANCE_ENDED)
        if ended_early and b_miss > self.capture_radius:
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
            run, encounters = ins_run(ins, path, sc, self.params, self.capture_radius)
        else:
            encounters = find_encounters(path, sc, self.capture_radius)
            run = corrections_run(path, encounters, sc, self.params, rng, self.capture_radius)
        missed = find_missed(
            self.nominal, path, encounters, sc, self.capture_radius, compiled=self.compiled,
            landmarks=self.mission_landmarks,
        )  # fmt: skip
        if ended_early:
            # The flight ended where it was lost (or out of endurance): a landmark whose
            # mission item it had not reached yet was not missed, just not reached.
            done = max((e.seq for e in flight.events if e.kind == "reached"), default=-1)
            missed = [m for m in missed if m.seq <= done]
        if any(m.distance <= run.flown_length for m in missed):
            run = replace(run, missed_before_loss=True)
        if flight.ended == guidance.ENDURANCE_ENDED and not run.reached_b and not run.lost:
            run = replace(run, out_of_endurance=True, lost_reason=self.spent(path))
        return run, flight, path, encounters, missed

    def spent(self, path: FlightPath) -> str:
        """Why a flight whose endurance ran out at the end of ``path`` was lost."""
        left = float(np.linalg.norm(path.points[-1] - self.scenario.xyz[self.scenario.end]))
        minutes = (self.endurance or 0.0) / 60.0
        return (
            f"out of endurance: the {minutes:g} min the aircraft can fly ran out {left:,.0f} m "
            "from B (the low-battery failsafe, ArduPlane BATT_FS_LOW_ACT / PX4 "
            "COM_LOW_BAT_ACT, ends the mission)"
        )


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
            lost.append(LostRun(run.missed_before_loss, failed, k, run.lost_reason, before,
                                run.out_of_endurance))  # fmt: skip
    low, high = wilson_interval(successes, runs, confidence)
    return MonteCarloSummary(
        runs, successes, successes / runs, low, high, confidence, flight_losses,
        runs - successes - flight_losses, flown=True, lost_runs=tuple(lost),
    )  # fmt: skip
