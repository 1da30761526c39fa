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

Its steps, one module each: what it is given (:mod:`.world`), the upload over the link
(:mod:`.upload`), the flight (:mod:`.flight`, its words in :mod:`.reasons`) and the report
(:mod:`.report`; its text in :mod:`.render`). This module runs them, and keeps the names callers
import from it.
"""

from __future__ import annotations

import time
from typing import Any

from gcs_planner.core.planner import Plan
from gcs_planner.dryrun.flight import (
    DEVIATION_STEP_M,
    DryRunRow,
    LostRunRow,
    as_planned,
    fly_stored_mission,
    lost_by_the_flight,
    max_deviation,
    stretch_overrun,
)
from gcs_planner.dryrun.reasons import plan_assumptions
from gcs_planner.dryrun.report import DryRunReport, build_report, length_tolerance
from gcs_planner.dryrun.upload import INT16_PARAMS, upload_mission
from gcs_planner.dryrun.world import (
    DRY_RUN_ACCEPTANCE_RADIUS_M,
    VEHICLE_REQUEST_TIMEOUT_S,
    DryRunSettings,
    DryRunWorld,
    records_of,
)
from gcs_planner.mission.builder import Mission, build_mission
from gcs_planner.mission.plan_json import plan_to_dict
from gcs_planner.mission.vehicle_setup import needs as setup_needs
from gcs_planner.scenario.model import Scenario
from gcs_planner.sim import (
    replay as replay_mod,  # the flight's module, as callers reach it from here
)
from gcs_planner.sim.faults import FaultRates
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

# The names callers import from this module, wherever they now live.
__all__ = [
    "DEVIATION_STEP_M",
    "DRY_RUN_ACCEPTANCE_RADIUS_M",
    "EXIT_LOST",
    "EXIT_RISKY",
    "INT16_PARAMS",
    "VEHICLE_REQUEST_TIMEOUT_S",
    "DryRunReport",
    "DryRunRow",
    "DryRunSettings",
    "DryRunWorld",
    "LostRunRow",
    "as_planned",
    "dry_run",
    "fly_dry_run",
    "length_tolerance",
    "lost_by_the_flight",
    "max_deviation",
    "plan_assumptions",
    "replay_mod",
    "stretch_overrun",
]

# Exit code of a dry run whose mission verified but whose replay did not arrive. Not an error
# class: the report is still printed in full, the code only tells a script the verdict.
EXIT_LOST = 5
# Exit code of a dry run that flew well but whose route arrives with a probability below the
# planner's threshold (--min-probability), unless --allow-risky: plan's own for such a route.
EXIT_RISKY = 3


def dry_run(
    plan: Plan, landmarks: Scenario, *, track: list | None = None, **options: Any
) -> DryRunReport:
    """Fly ``plan``'s chosen route on a mock vehicle whose landmark database is ``landmarks``:
    :func:`fly_dry_run` with the records of ``options``, each named as a field of
    :class:`~gcs_planner.dryrun.world.DryRunWorld` (``flavour``, ``wind``, ``design_wind``,
    ``navigate_on_estimate``, ``error_unit``, ``capture_radius``, ``flight_model``,
    ``set_params``, ``vehicle_as_is``) or of :class:`~gcs_planner.dryrun.world.DryRunSettings`
    (``runs``, ``seed``, ``loss``, ``timeout``, ``retries``, ``request_timeout``, ``attempts``,
    ``connect_timeout``, ``acceptance_radius``); ValueError for a value a flight cannot use,
    TypeError for another name."""
    world, settings = records_of(plan, landmarks, options)
    return fly_dry_run(world, settings, track)


def fly_dry_run(
    world: DryRunWorld, settings: DryRunSettings, track: list | None = None
) -> DryRunReport:
    """Export ``world``'s plan, upload it with its vehicle setup to a mock vehicle on loopback
    and read it back (gcs_planner/dryrun/upload.py), fly the mission the vehicle stored
    (gcs_planner/dryrun/flight.py) and report (gcs_planner/dryrun/report.py).

    The operator's workflow is flown: the plan's vehicle setup (``mission.vehicle_setup``:
    airspeed, climb and sink rates, roll limit, ArduPlane's NAVL1_LIM_BANK, loiter radius) is set
    with the mission, as ``upload --params`` sets the setup file (``world.set_params`` wins where
    both name one); with ``world.vehicle_as_is`` nothing of it is set and the report names what
    the vehicle falls short of (``setup_shortfalls``), the first cause of a loss. A lost final
    MISSION_ACK needs no second attempt: the mock vehicle answers the resent last item with the
    ACK again, as PX4 does since PX4-Autopilot#9547. ``track``: a list that receives the replay
    (sim/replay.ReplayReport) for a caller that writes the flown track. With a ``flight_model``
    (JSBSim) what the airframe cannot fly (``airframe_limits``) fails the verdict.
    """
    plan_dict = plan_to_dict(world.plan)
    # The plan's vehicle setup: set with the mission, or (as it is) what the vehicle lacks of it.
    wanted = setup_needs(plan_dict, world.flavour, world.setup_wind)
    mission = build_mission(
        plan_dict, firmware=world.flavour, acceptance_radius=settings.acceptance_radius
    )
    port = free_udp_port()
    vehicle = _mock_vehicle(port, world, settings, mission)
    started = time.perf_counter()
    with vehicle:
        setup = [] if world.vehicle_as_is else wanted
        uploaded = upload_mission(
            f"udpout:127.0.0.1:{port}",
            mission,
            world.flavour,
            setup,
            world.set_params,
            settings,
            started,
        )
        flight = fly_stored_mission(vehicle, world, settings, plan_dict, wanted)
        dropped = sum(
            inj.counts.dropped for inj in (vehicle.faults_out, vehicle.faults_in) if inj is not None
        )
    if track is not None:
        track.append(flight.replayed)
    return build_report(world, settings, plan_dict, mission, uploaded, flight, dropped)


def _mock_vehicle(
    port: int, world: DryRunWorld, settings: DryRunSettings, mission: Mission
) -> MockVehicle:
    """The mock vehicle on 127.0.0.1:``port``: ``world``'s autopilot and landmark database,
    room for the mission, and the link's seeded losses both ways."""
    faults = FaultRates(drop=settings.loss) if settings.loss > 0 else None
    return MockVehicle(
        f"udpin:127.0.0.1:{port}",
        scenario=world.landmarks,
        flavour=world.flavour,
        capacity=max(5000, len(mission.items)),
        faults_out=faults,
        faults_in=faults,
        fault_seed=settings.seed,
        capture_radius=world.capture_radius,
        request_timeout=settings.vehicle_request_timeout,
    )
