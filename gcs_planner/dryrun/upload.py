"""The dry run's upload over the link: the mission and the vehicle's setup sent to the mock
vehicle with the project's MAVLink client, read back and compared, as an operator loads them.

Only a read-back equal to the upload counts as verified. A failed upload is not raised: the
outcome says why (each attempt's error, in order), and the vehicle still flies whatever it
stored. A refusal (:class:`~gcs_planner.errors.UploadRefused`) is not tried again: asking again
gets the same answer.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from gcs_planner.aircraft.autopilot import AUTOPILOTS, PARAM_TYPE_INT16, autopilot_for
from gcs_planner.dryrun.world import DryRunSettings
from gcs_planner.errors import LinkError, UploadRefused
from gcs_planner.link.connection import Link, mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.params import set_parameter
from gcs_planner.link.vehicle_check import Shortfall, refusal
from gcs_planner.mission.builder import Mission
from gcs_planner.mission.vehicle_setup import ParameterNeed

# The integer parameters among those a dry run may set (the rest are floats): every autopilot's
# int16 ones (ArduPlane's WP_RADIUS and WP_LOITER_RAD).
INT16_PARAMS = frozenset(
    p.name for ap in AUTOPILOTS.values() for p in ap.params if p.ptype == PARAM_TYPE_INT16
)


@dataclass(frozen=True)
class UploadOutcome:
    """What the upload came to: ``verified`` (read back equal, every parameter confirmed), the
    error of each failed attempt in order, the seconds from the vehicle's start to the link's
    close, the ground station's resends, and the vehicle setup set with the mission (empty when
    the vehicle flies as it is or never answered)."""

    verified: bool
    errors: tuple[str, ...]
    seconds: float
    resends: int
    setup: tuple[ParameterNeed, ...]

    @property
    def attempts(self) -> int:
        return len(self.errors) + self.verified


def upload_mission(
    address: str,
    mission: Mission,
    flavour: str,
    setup: Sequence[ParameterNeed],
    set_params: Mapping[str, float] | None,
    settings: DryRunSettings,
    started: float,
) -> UploadOutcome:
    """Upload ``mission`` to the vehicle at ``address`` (a pymavlink connection string) and set
    its parameters: the plan's vehicle ``setup`` (empty: the vehicle flies as it is), the user's
    ``set_params`` winning, and the dry run's acceptance radius where ``flavour`` ignores a
    waypoint's own. Up to ``settings.attempts`` whole uploads; a setup no autopilot value can
    meet refuses the upload, naming it. ``started``: when the vehicle started
    (``time.perf_counter``), which the upload's seconds count from."""
    link = open_link(address)
    # The mission protocol, as before MissionClient's default became auto: its refusals
    # name the reason (NO_SPACE), which the dry run reports; MAVFTP's close says none.
    client = MissionClient(
        link, timeout=settings.timeout, retries=settings.retries, transfer="mission"
    )
    errors: list[str] = []
    verified = False
    set_up: tuple[ParameterNeed, ...] = ()
    try:
        client.connect(timeout=settings.connect_timeout)
        # The plan's vehicle setup, as the operator loads it with the mission (upload
        # --params): every parameter of it, the user's own --param values winning; as it
        # is, the vehicle's own values, and what falls short of the setup is reported.
        set_up = tuple(setup)
        impossible = [Shortfall(n, math.nan) for n in set_up if n.impossible]
        if impossible:
            raise LinkError(refusal(impossible, "plan for an aircraft this autopilot flies"))
        values = parameters_to_set(flavour, set_up, set_params, settings.acceptance_radius)
        loiter = mission.loiter_param[1] if mission.loiter_param else None
        for _ in range(settings.attempts):
            try:
                client.upload_verified(mission.items, loiter_radius=loiter)
                _set_parameters(link, client, values, settings)
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
    seconds = time.perf_counter() - started
    return UploadOutcome(verified, tuple(errors), seconds, client.retry_count, set_up)


def parameters_to_set(
    flavour: str,
    setup: Sequence[ParameterNeed],
    set_params: Mapping[str, float] | None,
    acceptance_radius: int,
) -> dict[str, float]:
    """The parameters set after the upload, in order: the plan's ``setup``, the user's
    ``set_params`` winning; first the vehicle-wide acceptance radius when the autopilot ignores
    a waypoint's own (PX4 on a fixed wing ignores param2)."""
    values = {n.name: n.set_to for n in setup}
    values.update(set_params or {})
    ap = autopilot_for(flavour)
    if not ap.item_acceptance:
        values = {ap.acceptance_param: float(acceptance_radius), **values}
    return values


def _set_parameters(
    link: Link, client: MissionClient, values: Mapping[str, float], settings: DryRunSettings
) -> None:
    """PARAM_SET each of ``values`` and see it confirmed (LinkError otherwise)."""
    for name, value in values.items():
        ptype = (
            mavlink.MAV_PARAM_TYPE_INT16 if name in INT16_PARAMS else mavlink.MAV_PARAM_TYPE_REAL32
        )
        set_parameter(
            link,
            client._target(),
            name,
            float(value),
            ptype,
            timeout=settings.timeout,
            retries=settings.retries,
        )
