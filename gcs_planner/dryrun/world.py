"""What a dry run is given: the world it flies (:class:`DryRunWorld`: the plan, the vehicle's
landmark database, the autopilot, the air, the vehicle's setup) and how it is run
(:class:`DryRunSettings`: runs, seed, the link's losses, waits and retries, the exported
acceptance radius).

Both records check their values when made (ValueError), so a dry run that starts is one whose
inputs a flight can use. :func:`records_of` turns the keyword arguments of
:func:`gcs_planner.dryrun.run.dry_run` into the two records.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any

from gcs_planner.aircraft.autopilot import AUTOPILOTS, DEFAULT_AUTOPILOT
from gcs_planner.core.planner import Plan
from gcs_planner.link.protocol import DEFAULT_RETRIES, DEFAULT_TIMEOUT_S
from gcs_planner.scenario.model import Scenario
from gcs_planner.sim.ins import DEFAULT_ERROR_UNIT_M
from gcs_planner.sim.replay import DEFAULT_CAPTURE_RADIUS_M
from gcs_planner.sim.wind import WindSpec

# ArduPilot's wait before it asks again for a mission item it has not received.
VEHICLE_REQUEST_TIMEOUT_S = 1.0
# The waypoint acceptance radius the dry run exports with (gcs_planner/dryrun/run.py's
# docstring): the autopilot flies up to each point rather than turning early.
DRY_RUN_ACCEPTANCE_RADIUS_M = 1


@dataclass(frozen=True)
class DryRunWorld:
    """The world a dry run flies.

    ``plan``: the plan whose chosen route is flown; ``landmarks``: the vehicle's landmark
    database (a scenario loaded on its own, as a real aircraft carries its correction map);
    ``flavour``: the autopilot flown (a name of ``AUTOPILOTS``). The flight: ``wind``
    (sim/wind.py; None: still air; a direction not given is drawn per flight), the aircraft
    steering its INS estimate (``navigate_on_estimate``, ``error_unit`` metres per error unit),
    landmarks corrected within ``capture_radius`` metres (3D), and ``flight_model``
    (sim/jsbsim_airframe.py ``FlightModel``; None: the point mass). The vehicle's setup:
    ``set_params`` (autopilot parameters under the vehicle's own names, set after the upload;
    they win over the plan's setup), ``vehicle_as_is`` (the plan's setup is not set: the vehicle
    flies at its own parameters) and ``design_wind`` (m/s; None: the wind flown), the wind the
    setup's rates and bank hold in when the plan's envelope was stated rather than derived.
    ``endurance``: the minutes of flight the aircraft has (None: unlimited); a flight that has
    not come to B by then is lost by the flight (gcs_planner/dryrun/endurance.py).
    """

    plan: Plan
    landmarks: Scenario
    flavour: str = DEFAULT_AUTOPILOT
    wind: WindSpec | None = None
    endurance: float | None = None
    design_wind: float | None = None
    navigate_on_estimate: bool = True
    error_unit: float = DEFAULT_ERROR_UNIT_M
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M
    flight_model: object | None = None
    set_params: Mapping[str, float] | None = None
    vehicle_as_is: bool = False

    def __post_init__(self) -> None:
        if self.flavour not in AUTOPILOTS:
            known = tuple(AUTOPILOTS)
            raise ValueError(f"flavour must be one of {known}, got {self.flavour!r}")
        if self.endurance is not None and not 0 < self.endurance < float("inf"):
            raise ValueError(f"endurance must be minutes > 0, got {self.endurance!r}")

    @property
    def air(self) -> WindSpec:
        """The wind flown (still air when none is given)."""
        return self.wind or WindSpec()

    @property
    def setup_wind(self) -> float:
        """The wind (m/s) the plan's vehicle setup must hold in: ``design_wind``, else the wind
        flown."""
        return self.air.speed if self.design_wind is None else self.design_wind


@dataclass(frozen=True)
class DryRunSettings:
    """How a dry run is run.

    ``runs`` > 0 adds a Monte Carlo of that many flights. ``loss``: the fraction of MAVLink
    messages the vehicle drops, both ways (seeded by ``seed``, which also seeds the flight's
    draws). ``timeout`` and ``retries`` are the ground station's (QGroundControl's 1.5 s and 5
    by default), ``request_timeout`` the vehicle's wait before it asks for an item again (None:
    :attr:`vehicle_request_timeout`). ``attempts``: whole uploads tried before giving up, as a
    user would press upload again when heavy ``loss`` outlasts the ground station's retries.
    ``connect_timeout``: the wait for the vehicle's heartbeat. ``acceptance_radius``: the
    waypoint acceptance radius exported and set on the vehicle (whole metres).
    """

    runs: int = 0
    seed: int = 0
    loss: float = 0.0
    timeout: float = DEFAULT_TIMEOUT_S
    retries: int = DEFAULT_RETRIES
    request_timeout: float | None = None
    attempts: int = 3
    connect_timeout: float = 10.0
    acceptance_radius: int = DRY_RUN_ACCEPTANCE_RADIUS_M

    def __post_init__(self) -> None:
        if self.runs < 0:
            raise ValueError("runs must be >= 0")
        if self.attempts < 1:
            raise ValueError("attempts must be >= 1")
        if not 0.0 <= self.loss < 1.0:
            raise ValueError(f"loss must lie in [0, 1), got {self.loss!r}")

    @property
    def vehicle_request_timeout(self) -> float:
        """The vehicle's wait before it asks again for an item: ``request_timeout``, else
        ArduPilot's 1 s, shortened when the ground station's patience (``timeout`` times
        ``retries + 1``) would not cover four of them. The ground station gives up on a lost
        request even while the vehicle answers its resent item with INVALID_SEQUENCE, so the
        vehicle's own re-request must come well within that patience."""
        if self.request_timeout is not None:
            return self.request_timeout
        return min(VEHICLE_REQUEST_TIMEOUT_S, self.timeout * (self.retries + 1) / 4)


_WORLD_FIELDS = frozenset(f.name for f in fields(DryRunWorld)) - {"plan", "landmarks"}
_SETTINGS_FIELDS = frozenset(f.name for f in fields(DryRunSettings))


def records_of(
    plan: Plan, landmarks: Scenario, options: Mapping[str, Any]
) -> tuple[DryRunWorld, DryRunSettings]:
    """The world and the settings of :func:`~gcs_planner.dryrun.run.dry_run`'s keyword
    arguments, each named as the field of its record; TypeError for a name neither has."""
    unknown = sorted(set(options) - _WORLD_FIELDS - _SETTINGS_FIELDS)
    if unknown:
        raise TypeError(f"dry_run() got an unexpected keyword argument {unknown[0]!r}")
    world = DryRunWorld(plan, landmarks, **{k: v for k, v in options.items() if k in _WORLD_FIELDS})
    settings = DryRunSettings(**{k: v for k, v in options.items() if k in _SETTINGS_FIELDS})
    return world, settings
