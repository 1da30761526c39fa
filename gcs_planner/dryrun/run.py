"""The dry run: a plan checked end to end against the mock vehicle, over real MAVLink on loopback.

plan -> plan JSON -> mission items (the exporter) -> upload with the project's client to a
:class:`~sim.vehicle.MockVehicle` on 127.0.0.1 -> read back and compare -> the vehicle replays
the mission it *stored* against its own landmark database -> report.

The vehicle is given nothing of the planner's: only a scenario the caller loaded on its own (the
CLI reads the file a second time), as a real aircraft would carry its correction map. The report
then compares what the vehicle flew with what the plan promised: the stored mission's length
within the exporter's stated tolerance (sim/replay.py: chord shortfall on densified arcs plus the
degE7 quantisation of every waypoint), the FLOWN track (sim/guidance.py: the autopilot in mode
AUTO with the scenario's vehicle profile, whatever leg model planned the route) against the
mission's path (largest deviation, flown against planned length), each planned correction made,
failed or missed with its 3D miss distance, and with ``runs`` the Monte Carlo success rate
against the plan's exact probability (the path is flown once, the draws at unreliable points
repeated).

The mission is exported with a small waypoint ACCEPTANCE radius (``acceptance_radius``, 1 m:
param2 of the waypoints for ArduPlane, the vehicle's NAV_ACC_RAD for PX4, which ignores param2
on a fixed wing) so that ArduPlane flies up to each point and passes its finish line rather than
turning up to 90 m early. PX4 still switches at npfg's switch distance (~56 m at 25 m/s): the
flight says what that does.

The flight is in the real world (issue 26; sim/guidance.py): the autopilot's own parameters as
the vehicle holds them (shipped defaults unless set, ``set_params``), its true airspeed at
altitude, the wind (``wind``), and the INS estimate it steers (``navigate_on_estimate``). With
``runs`` every run is a flight of its own and the verdict (``DryRunReport.ok``) asks that no run
was lost by the flight and that the success rate is consistent with the planned probability;
without runs the seeded flight is a demonstration. The report states what the plan assumed that
the flight does not (unlimited climb, still air, EAS as TAS).
"""

from __future__ import annotations

import math
import time
from collections.abc import Collection
from dataclasses import asdict, dataclass

import numpy as np
from scipy.spatial import cKDTree

from gcs_planner.aircraft.autopilot import effective, keeps_home_item
from gcs_planner.aircraft.envelope_fit import LegShortfall, legs_outside_envelope
from gcs_planner.core.planner import Plan
from gcs_planner.core.probability import outcomes
from gcs_planner.core.route import Route
from gcs_planner.errors import LinkError, UploadRefused
from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.params import set_parameter
from gcs_planner.link.protocol import DEFAULT_RETRIES, DEFAULT_TIMEOUT_S
from gcs_planner.link.vehicle_check import Shortfall, refusal, shortfalls
from gcs_planner.mission.builder import build_mission
from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.items import HELIX_COMMANDS
from gcs_planner.mission.plan_json import plan_to_dict
from gcs_planner.mission.vehicle_setup import needs as setup_needs
from gcs_planner.scenario.model import Parameters, Scenario
from sim import replay as replay_mod
from sim.faults import FaultRates
from sim.guidance import AutopilotParams
from sim.ins import DEFAULT_ERROR_UNIT_M
from sim.vehicle import FLAVOURS, MockVehicle, free_udp_port
from sim.wind import WindSpec

# Exit code of a dry run whose mission verified but whose replay did not arrive. Not an error
# class: the report is still printed in full, the code only tells a script the verdict.
EXIT_LOST = 5
# Exit code of a dry run that flew well but whose route arrives with a probability below the
# planner's threshold (--min-probability), unless --allow-risky: plan's own for such a route.
EXIT_RISKY = 3
# ArduPilot's wait before it asks again for a mission item it has not received.
VEHICLE_REQUEST_TIMEOUT_S = 1.0
# The waypoint acceptance radius the dry run exports with (see module docstring).
DRY_RUN_ACCEPTANCE_RADIUS_M = 1
# PX4's acceptance radius parameter (fixed wing: param2 is not used).
PX4_ACCEPTANCE_PARAM = "NAV_ACC_RAD"
# ArduPlane's integer parameters among those a dry run may set (the rest are floats).
INT16_PARAMS = frozenset({"WP_RADIUS", "WP_LOITER_RAD"})
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


@dataclass(frozen=True)
class DryRunReport:
    scenario: str
    flavour: str
    route: tuple[str, ...]  # planned point ids, A..B
    verified: bool
    link_error: str  # why the upload did not verify ("" when it did)
    upload_attempts: int
    upload_errors: tuple[str, ...]  # of the attempts that failed, in order
    items: int
    upload_seconds: float
    resends: int
    messages_dropped: int
    loss: float
    seed: int
    arrived: bool
    lost_reason: str
    why: str  # where and which limit, when not arrived
    flown_length: float  # to B, or to where the vehicle was lost
    mission_length: float  # of the stored mission's path to B, whatever the draw
    planned_length: float
    arc_length: float
    waypoints: int
    length_tolerance: float
    rows: tuple[DryRunRow, ...]
    corrections_as_planned: bool  # the path meets the planned points, in order, and no other
    v_at_b: float
    h_at_b: float
    theta: float
    planned_probability: float
    flown_to_b: float = 0.0  # the flown track to its closest approach to B (or its loss before)
    flight_seconds: float = 0.0
    flight_ended: str = ""
    max_deviation: float = 0.0  # largest 3D distance of the flown track from the mission's path
    max_deviation_at: float = 0.0  # flown from A, metres
    acceptance_radius: float = DRY_RUN_ACCEPTANCE_RADIUS_M
    capture_radius: float = 0.0
    flight_notes: tuple[str, ...] = ()
    helices: int = 0  # loiter items of the mission (the planner's helices)
    runs: int = 0
    success_rate: float | None = None
    success_ci: tuple[float, float] | None = None
    confidence: float | None = None
    # The plan's flight reserve, and the most the flight flew beyond the plan between two
    # corrections of the same error (what the reserve must cover); None when no stretch of the
    # route was flown from end to end.
    reserve: float = 0.0
    max_overrun: float | None = None
    # The flight's world: the wind flown, the autopilot's limits, whether the aircraft steered
    # its INS estimate, and what the plan assumed that the flight does not (unlimited climb,
    # still air).
    wind: str = "still air"
    autopilot: str = ""
    navigate_on_estimate: bool = False
    assumptions: tuple[str, ...] = ()
    # Runs lost by the flight (a missed landmark, or lost where the plan flown as planned
    # with the same correction outcomes arrives: ``lost_by_the_flight``) and by failed
    # corrections; the seeded flight's own verdict.
    flight_losses: int = 0
    correction_losses: int = 0
    runs_flown: bool = False  # each run flown on its own (wind, gusts, estimate drawn per run)
    flight_lost: bool = False  # the seeded flight was lost by the flight
    # Every lost run of the Monte Carlo: where and why, what it missed and where its
    # corrections failed before, and whether it counts as lost by the flight.
    lost_runs: tuple[LostRunRow, ...] = ()
    # The flight model (sim/jsbsim_airframe.py with --flight-model jsbsim), what it found
    # before the flight that the airframe cannot fly (where and why: the mission cannot be
    # flown as planned) and what it could not hold in flight.
    flight_model: str = "point mass"
    airframe_limits: tuple[str, ...] = ()
    airframe_shortfalls: tuple[str, ...] = ()
    # Checked before the flight (gcs_planner/aircraft/envelope_fit.py): every leg that does not fit
    # the
    # plan's aircraft's envelope in the wind flown (``envelope_wind`` m/s, any direction), with
    # what it needs and what the aircraft can do; None when the plan states no aircraft in
    # the autopilot's terms (no envelope to derive: the flight is the only judge).
    envelope_shortfalls: tuple[LegShortfall, ...] = ()
    envelope_wind: float | None = None
    # the flown wind's direction (degrees it blows from): the climbs are checked along each
    # leg's track; None: from any direction
    envelope_wind_from: float | None = None
    # The plan's vehicle setup (``mission.vehicle_setup``) as set on the vehicle ("NAME=VALUE";
    # empty when the vehicle flew as it is), and what the vehicle's parameters fell short of
    # it when it flew (the first cause of a loss when the vehicle was not set up).
    setup: tuple[str, ...] = ()
    vehicle_as_is: bool = False
    setup_shortfalls: tuple[str, ...] = ()

    @property
    def demonstration(self) -> bool:
        """Without runs the one seeded flight shows what can happen; it is no verdict."""
        return self.runs == 0

    @property
    def length_difference(self) -> float:
        return self.mission_length - self.planned_length

    @property
    def length_within_tolerance(self) -> bool | None:
        """The stored mission's chords against the planned length; None when the mission has
        helices (loiters), which its chords cannot measure (the flight does)."""
        if self.helices:
            return None
        return abs(self.length_difference) <= self.length_tolerance

    @property
    def probability_within_ci(self) -> bool | None:
        """The Monte Carlo agrees with the plan: the planned probability within the interval;
        with a flight reserve the plan's probability is a floor (held to limits lowered by the
        reserve), so the promise is kept when it is not above the interval."""
        if self.success_ci is None:
            return None
        low, high = self.success_ci
        if self.reserve > 0:
            return self.planned_probability <= high
        return low <= self.planned_probability <= high

    @property
    def flown_difference(self) -> float:
        return self.flown_to_b - self.planned_length

    @property
    def missed(self) -> tuple[DryRunRow, ...]:
        return tuple(r for r in self.rows if r.outcome == "missed")

    @property
    def ok(self) -> bool:
        """The verdict: verified, and with runs no run lost by the flight and the success rate
        consistent with the planned probability; without runs (a demonstration) the seeded
        flight arrived."""
        # A plan whose legs do not fit the envelope in the wind flown fails whatever the runs
        # drew: the runs fly the legs they reach in the directions they drew, and a shortfall
        # they survive is survived on the flight reserve and the capture radius, which the plan
        # keeps for what it cannot foresee (dataset 2's still-air plan in 5 m/s: issue 32).
        if not self.verified or self.airframe_limits or self.envelope_shortfalls:
            return False
        if self.runs == 0:
            return self.arrived
        return self.flight_losses == 0 and bool(self.probability_within_ci)

    def to_dict(self) -> dict:
        out = asdict(self)
        if not self.verified:
            # Nothing flew: no flight, no rate, no losses to speak of.
            out = {k: out[k] for k in _UPLOAD_KEYS}
            out["route"] = list(self.route)
            out["ok"] = False
            out["flown"] = False
            return out
        out["flown"] = True
        out["route"] = list(self.route)
        out["length_difference"] = self.length_difference
        out["length_within_tolerance"] = self.length_within_tolerance
        out["ok"] = self.ok
        out["demonstration"] = self.demonstration
        # A missed landmark has no errors on arrival: null, not NaN (JSON has no NaN).
        out["rows"] = [
            {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()}
            for row in out["rows"]
        ]
        out["flown_difference"] = self.flown_difference
        if self.runs > 0:
            out["success_ci"] = list(self.success_ci or ())
            out["probability_within_ci"] = self.probability_within_ci
        else:
            for key in ("success_rate", "success_ci", "confidence"):
                del out[key]
        return out


# What a report of a mission that never verified (and so never flew) says.
_UPLOAD_KEYS = (
    "scenario", "flavour", "route", "verified", "link_error", "upload_attempts",
    "upload_errors", "items", "upload_seconds", "resends", "messages_dropped", "loss", "seed",
    "planned_length", "planned_probability", "setup", "vehicle_as_is",
)  # fmt: skip


def length_tolerance(arc_length: float, waypoints: int) -> float:
    """How far the flown length may be from the planned one (sim/replay.py): chords under the
    densified arcs are short by at most ``CHORD_SHORTFALL`` of the arc, and each waypoint's
    degE7 position moves it by at most ``QUANTISATION_M``."""
    return replay_mod.CHORD_SHORTFALL * arc_length + replay_mod.QUANTISATION_M * waypoints


def dry_run(
    plan: Plan,
    landmarks: Scenario,
    *,
    flavour: str = "ardupilot",
    runs: int = 0,
    loss: float = 0.0,
    seed: int = 0,
    capture_radius: float = replay_mod.DEFAULT_CAPTURE_RADIUS_M,
    timeout: float = DEFAULT_TIMEOUT_S,
    retries: int = DEFAULT_RETRIES,
    request_timeout: float | None = None,
    attempts: int = 3,
    connect_timeout: float = 10.0,
    acceptance_radius: int = DRY_RUN_ACCEPTANCE_RADIUS_M,
    track: list | None = None,
    wind: WindSpec | None = None,
    navigate_on_estimate: bool = True,
    error_unit: float = DEFAULT_ERROR_UNIT_M,
    set_params: dict[str, float] | None = None,
    vehicle_as_is: bool = False,
    flight_model: object | None = None,
    design_wind: float | None = None,
) -> DryRunReport:
    """Fly ``plan``'s chosen route on a mock vehicle whose landmark database is ``landmarks``.

    ``loss``: the fraction of MAVLink messages the vehicle drops, both ways (seeded by ``seed``,
    which also seeds the replay's draws at unreliable points). ``runs`` > 0 adds a Monte Carlo
    of that many replays. ``timeout`` and ``retries`` are the ground station's (QGroundControl's
    1.5 s and 5 by default), ``request_timeout`` the vehicle's wait before it asks for an item
    again: ArduPilot's 1 s, shortened when the ground station's patience (``timeout`` times
    ``retries + 1``) would not cover four of them. The ground station gives up on a lost
    request even while the vehicle answers its resent item with INVALID_SEQUENCE, so the
    vehicle's own re-request must come well within that patience.

    ``attempts``: whole uploads tried before giving up, as a user would press upload again when
    heavy ``loss`` outlasts the ground station's retries. (A lost final MISSION_ACK no longer
    needs this: the mock vehicle answers the resent last item with the ACK again, as PX4 does
    since PX4-Autopilot#9547.) Only a read-back equal to the upload counts as verified; a
    refusal (MAV_MISSION_RESULT) is not retried. A failed upload is not raised: the report says
    ``verified`` False and why, and the vehicle still replays whatever it stored.

    ``acceptance_radius``: the waypoint acceptance radius exported and set on the vehicle (see
    the module docstring). ``track``: a list that receives the replay (sim/replay.ReplayReport)
    for a caller that writes the flown track.

    The flight: ``wind`` (sim/wind.py; default still air; a direction not given is drawn per
    flight), the aircraft steering its INS estimate (``navigate_on_estimate``, ``error_unit``
    metres per error unit) with the autopilot's own parameters as the vehicle holds them. With
    ``runs`` > 0 each run is flown on its own with its own draws (wind direction, gusts, error
    directions, outcomes) unless nothing in the flight is drawn. ``set_params``: autopilot
    parameters (the vehicle's own names, e.g. TECS_CLMB_MAX, NAVL1_LIM_BANK, FW_T_CLMB_R_SP)
    the ground station sets over the link after the upload, as a user configures the aircraft;
    a parameter the vehicle does not confirm is an upload error. The operator's workflow is
    flown: the plan's vehicle setup (``mission.vehicle_setup``: airspeed, climb and sink rates,
    roll limit, ArduPlane's NAVL1_LIM_BANK, loiter radius) is set with the mission, as
    ``upload --params`` sets the setup file (``set_params`` wins where both name one). A setup
    no autopilot value can meet refuses the upload, naming it. ``vehicle_as_is``: nothing of the
    setup is set, the vehicle flies at its own parameters, and the report names what falls
    short of the setup (``setup_shortfalls``), the first cause of a loss. ``design_wind``
    (m/s; default the wind flown): the wind the plan was made for, which the setup's rates and
    bank hold in when the plan's envelope was stated rather than derived (the setup file
    ``plan --wind`` writes).

    ``flight_model`` (sim/jsbsim_airframe.py ``FlightModel``; default the point mass) flies the
    replay in JSBSim: what the airframe cannot fly (``airframe_limits``) fails the verdict.
    """
    if flavour not in FLAVOURS:
        raise ValueError(f"flavour must be one of {FLAVOURS}, got {flavour!r}")
    if runs < 0:
        raise ValueError("runs must be >= 0")
    if attempts < 1:
        raise ValueError("attempts must be >= 1")
    if not 0.0 <= loss < 1.0:
        raise ValueError(f"loss must lie in [0, 1), got {loss!r}")
    if request_timeout is None:
        request_timeout = min(VEHICLE_REQUEST_TIMEOUT_S, timeout * (retries + 1) / 4)
    route = plan.route
    plan_dict = plan_to_dict(plan)
    design = (wind or WindSpec()).speed if design_wind is None else design_wind
    # The plan's vehicle setup: set with the mission, or (as it is) what the vehicle lacks of it.
    wanted = setup_needs(plan_dict, flavour, design)
    mission = build_mission(plan_dict, firmware=flavour, acceptance_radius=acceptance_radius)
    loiter = mission.loiter_param[1] if mission.loiter_param else None
    faults = FaultRates(drop=loss) if loss > 0 else None
    port = free_udp_port()
    vehicle = MockVehicle(
        f"udpin:127.0.0.1:{port}",
        scenario=landmarks,
        flavour=flavour,
        capacity=max(5000, len(mission.items)),
        faults_out=faults,
        faults_in=faults,
        fault_seed=seed,
        capture_radius=capture_radius,
        request_timeout=request_timeout,
    )
    verified, errors = False, []
    setup: list = []
    start = time.perf_counter()
    with vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        # The mission protocol, as before MissionClient's default became auto: its refusals
        # name the reason (NO_SPACE), which the dry run reports; MAVFTP's close says none.
        client = MissionClient(link, timeout=timeout, retries=retries, transfer="mission")
        try:
            client.connect(timeout=connect_timeout)
            # The plan's vehicle setup, as the operator loads it with the mission (upload
            # --params): every parameter of it, the user's own --param values winning; as it
            # is, the vehicle's own values, and what falls short of the setup is reported.
            setup = [] if vehicle_as_is else wanted
            impossible = [Shortfall(n, math.nan) for n in setup if n.impossible]
            if impossible:
                raise LinkError(refusal(impossible, "plan for an aircraft this autopilot flies"))
            for _ in range(attempts):
                try:
                    client.upload_verified(mission.items, loiter_radius=loiter)
                    settings = {n.name: n.set_to for n in setup}
                    settings.update(set_params or {})
                    if flavour == "px4":
                        settings = {PX4_ACCEPTANCE_PARAM: float(acceptance_radius), **settings}
                    for name, value in settings.items():
                        ptype = (
                            mavlink.MAV_PARAM_TYPE_INT16
                            if name in INT16_PARAMS
                            else mavlink.MAV_PARAM_TYPE_REAL32
                        )
                        set_parameter(
                            link,
                            client._target(),
                            name,
                            float(value),
                            ptype,
                            timeout=timeout,
                            retries=retries,
                        )
                except LinkError as exc:
                    errors.append(str(exc))
                    if isinstance(exc, UploadRefused):
                        break  # the vehicle said no: asking again gets the same answer
                else:
                    verified = True
                    break
        except LinkError as exc:  # no heartbeat: nothing to retry
            errors.append(str(exc))
        finally:
            link.close()
        upload_seconds = time.perf_counter() - start
        # The vehicle's stored mission and parameters, flown with the world's options (the mock
        # vehicle's own replay() knows no wind nor INS navigation yet).
        held = vehicle.parameters
        autopilot = AutopilotParams.from_parameters(flavour, held)
        short = shortfalls(
            plan_dict, flavour, lambda name: held.get(name, math.nan),
            wanted,
        )  # fmt: skip
        # Before the flight: the plan's legs against its aircraft's envelope in the wind flown,
        # with the flown autopilot's settle distance as the vehicle holds its parameters.
        flown_wind = (wind or WindSpec()).speed
        settle = effective(flavour, vehicle.parameters).settle_distance
        envelope_shortfalls = legs_outside_envelope(
            plan.scenario, route.points, flown_wind, settle, (wind or WindSpec()).from_deg
        )
        replayed = replay_mod.replay(
            vehicle.mission,
            landmarks,
            seed=seed,
            runs=runs,
            home_at_seq0=keeps_home_item(flavour),
            capture_radius=capture_radius,
            cruise_speed=vehicle.cruise_speed,
            flavour=flavour,
            autopilot=autopilot,
            wind=wind,
            navigate_on_estimate=navigate_on_estimate,
            error_unit=error_unit,
            flight_model=flight_model,
        )
        dropped = sum(
            inj.counts.dropped for inj in (vehicle.faults_out, vehicle.faults_in) if inj is not None
        )

    if track is not None:
        track.append(replayed)
    planned = {s.id: s for s in route.stops[1:-1]}
    misses = {e.id: e.miss for e in replayed.encounters}
    rows = [_row(c, planned, misses.get(c.id, 0.0)) for c in replayed.run.corrections]
    end = replayed.flown_length
    rows += [_missed_row(m, planned) for m in replayed.missed if m.distance <= end]
    rows.sort(key=lambda r: r.distance)
    dev, dev_at = max_deviation(replayed, trajectory_local(plan_dict, step=DEVIATION_STEP_M))
    arcs = sum(s.leg.arc for s in route.stops if s.leg is not None)
    mc = replayed.monte_carlo
    lost_runs: list[LostRunRow] = []
    if mc is not None:
        params = plan.scenario.params
        lost_runs = [
            LostRunRow(r.run, r.reason, r.missed_ids, r.failed,
                       lost_by_the_flight(route, params, r.missed, r.failed))
            for r in mc.lost_runs
        ]  # fmt: skip
    flight_losses = sum(r.by_the_flight for r in lost_runs)
    return DryRunReport(
        scenario=landmarks.name,
        flavour=flavour,
        route=tuple(route.ids()),
        verified=verified,
        link_error="" if verified else errors[-1],
        upload_attempts=len(errors) + verified,
        upload_errors=tuple(errors),
        items=len(mission.items),
        upload_seconds=upload_seconds,
        resends=client.retry_count,
        messages_dropped=dropped,
        loss=loss,
        seed=seed,
        arrived=replayed.arrived,
        lost_reason=replayed.run.lost_reason,
        why=_why(replayed, [r for r in rows if r.outcome == "missed"]),
        flown_length=replayed.flown_length,
        mission_length=replayed.mission_length,
        planned_length=route.length,
        arc_length=arcs,
        waypoints=replayed.waypoints,
        length_tolerance=length_tolerance(arcs, replayed.waypoints),
        rows=tuple(rows),
        # The landmarks the path meets do not depend on the draw, only their outcomes do.
        corrections_as_planned=as_planned(
            [e.id for e in replayed.encounters], list(planned), replayed
        ),  # fmt: skip
        v_at_b=replayed.run.v_at_end,
        h_at_b=replayed.run.h_at_end,
        theta=replayed.theta,
        planned_probability=route.probability,
        runs=runs,
        success_rate=None if mc is None else mc.success_rate,
        success_ci=None if mc is None else (mc.ci_low, mc.ci_high),
        confidence=None if mc is None else mc.confidence,
        flown_to_b=replayed.flown.length if replayed.flown is not None else 0.0,
        flight_seconds=replayed.flight_time_s,
        flight_ended=replayed.flight.ended if replayed.flight is not None else "",
        max_deviation=dev,
        max_deviation_at=dev_at,
        acceptance_radius=float(acceptance_radius),
        capture_radius=capture_radius,
        flight_notes=replayed.flight.notes if replayed.flight is not None else (),
        # the helices' loiters; the last item (the end action) is not one of them
        helices=sum(it.command in HELIX_COMMANDS for it in mission.items[:-1]),
        reserve=plan.scenario.params.reserve,
        max_overrun=stretch_overrun(
            route, rows, replayed.flown.length if replayed.arrived and replayed.flown else None
        ),
        wind=(wind or WindSpec()).describe(),
        autopilot=autopilot.describe(),
        navigate_on_estimate=navigate_on_estimate,
        assumptions=plan_assumptions(plan, wind),
        flight_losses=flight_losses,
        correction_losses=0 if mc is None else mc.runs - mc.successes - flight_losses,
        runs_flown=False if mc is None else mc.flown,
        flight_lost=not replayed.run.arrived
        and lost_by_the_flight(
            route,
            plan.scenario.params,
            replayed.run.missed_before_loss,
            [c.id for c in replayed.run.corrections if c.succeeded is False],
        ),
        lost_runs=tuple(lost_runs),
        envelope_shortfalls=tuple(envelope_shortfalls),
        envelope_wind=flown_wind if plan.scenario.envelope is not None else None,
        envelope_wind_from=(wind or WindSpec()).from_deg,
        setup=tuple(f"{n.name}={n.set_to:g}" for n in setup),
        vehicle_as_is=vehicle_as_is,
        setup_shortfalls=tuple(sh.describe() for sh in short),
        **_airframe(replayed),
    )


def _airframe(replayed: replay_mod.ReplayReport) -> dict:
    """The flight model's fields of the report."""
    flight = replayed.flight
    if flight is None:
        return {}
    return {
        "flight_model": flight.flight_model,
        "airframe_limits": flight.limits,
        "airframe_shortfalls": flight.shortfalls,
    }


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


def plan_assumptions(plan: Plan, wind: WindSpec | None = None) -> tuple[str, ...]:
    """What the plan assumed of the aircraft that the flight does not give it."""
    v = plan.scenario.vehicle
    out = []
    if not v.climb_limited:
        out.append(
            "the plan assumed unlimited climb and descent (90 deg, the contest's model); the "
            "aircraft climbs and sinks at its autopilot's rates"
        )
    if v.turn_radius <= 0:
        out.append("the plan assumed turns on the spot (R = 0): so does this flight")
    flown = "" if wind is None or wind.still else f"; this flight: {wind.describe()}"
    env = plan.scenario.envelope
    if env is not None and env.wind > 0:
        where = (
            f"from {env.wind_from:g} deg only (each leg along its own track)"
            if env.along_track
            else "from any direction"
        )
        out.append(f"the plan's envelope holds in a design wind of {env.wind:g} m/s {where}{flown}")
    else:
        out.append(f"the plan assumed still air{flown}")
    if env is None and wind is not None and wind.speed > 0:
        out.append(
            "the plan states no aircraft in the autopilot's terms (rates, bank, airspeed): its "
            "legs are not checked against the envelope in the wind flown; the flight judges"
        )
    if env is not None:
        each = (
            "; each leg at the TAS of its own highest point, down to "
            f"{env.tas_low:.1f} m/s at {env.lowest_altitude:.0f} m"
            if env.per_leg
            else ""
        )
        out.append(
            f"the plan took {env.eas:g} m/s EAS as {env.tas:.1f} m/s TAS at "
            f"{env.altitude:.0f} m (ISA, the highest point){each}"
        )
    else:
        out.append(
            f"the plan assumed {v.cruise_airspeed:g} m/s over the air; the aircraft holds it "
            "as EAS and flies faster at altitude (ISA)"
        )
    return tuple(out)


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


def _why(report: replay_mod.ReplayReport, missed: list[DryRunRow] | None = None) -> str:
    limits = report.flight.limits if report.flight is not None else ()
    if limits:
        more = f" (and {len(limits) - 1} more)" if len(limits) > 1 else ""
        return f"the airframe cannot fly the mission: {limits[0]}{more}"
    return _why_flown(report, missed)


def _why_flown(report: replay_mod.ReplayReport, missed: list[DryRunRow] | None = None) -> str:
    """Where the vehicle was lost and which limit broke, with the numbers, and the corrections
    the flight missed on the way ("" if it arrived)."""
    run = report.run
    if run.arrived:
        return ""
    reason = _lost_reason(report)
    if missed:
        passes = ", ".join(
            f"{r.kind} point {r.point} (passed {r.miss:.1f} m away, {r.distance:,.0f} m from A)"
            for r in missed
        )
        reason += f"; the flight missed {passes}: outside the {report.capture_radius:g} m capture"
        reason += " radius"
    return reason


def _lost_reason(report: replay_mod.ReplayReport) -> str:
    run = report.run
    if run.corrections and not run.corrections[-1].within_limits:
        c = run.corrections[-1]
        broken = []
        if c.v_margin < 0:
            broken.append(f"vertical error {c.v_before:.3f} > limit {c.v_limit:g}")
        if c.h_margin < 0:
            broken.append(f"horizontal error {c.h_before:.3f} > limit {c.h_limit:g}")
        failed = [r.id for r in run.corrections if r.succeeded is False]
        cause = f" after the failed correction(s) at {', '.join(failed)}" if failed else ""
        return (
            f"lost at {c.kind} point {c.id}, {c.distance:,.1f} m from A: "
            f"{' and '.join(broken) or 'an error over its limit'}{cause}"
        )
    if not run.reached_b:
        return run.lost_reason or "the mission does not reach B"
    where = f"{run.flown_length:,.1f} m from A"
    broken = [
        f"{name} error {value:.3f} > theta {report.theta:g}"
        for name, value in (("vertical", run.v_at_end), ("horizontal", run.h_at_end))
        if value > report.theta
    ]
    failed = [r.id for r in run.corrections if r.succeeded is False]
    cause = f" after the failed correction(s) at {', '.join(failed)}" if failed else ""
    return f"lost at B, {where}: {' and '.join(broken) or 'an error over theta'}{cause}"
