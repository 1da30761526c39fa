"""The ground-station side of the MAVLink mission protocol: upload, download, clear, set current.

One :class:`MissionClient` per vehicle, a facade over one work item per transfer:
:mod:`~gcs_planner.link.session` (the vehicle, our heartbeat, its messages, the pace),
:mod:`~gcs_planner.link.mission_upload`, :mod:`~gcs_planner.link.mission_download` and
:mod:`~gcs_planner.link.mission_read_back` (the mission protocol's transfers and the
read-back), :mod:`~gcs_planner.link.mission_by_ftp` (the mission as ``@MISSION/mission.dat``
over MAVFTP), :mod:`~gcs_planner.link.mission_commands` (clear, set current, the loiter-radius
check) and :mod:`~gcs_planner.link.verified_upload` (upload, verify, set the loiter radius);
:mod:`~gcs_planner.link.outcome` holds what they come to.

Every wait has a deadline (1.5 s by default; for a single item the measured round trip, 0.25 s
as the specification recommends until there is one) and a transfer that makes no progress for
its retries of the timeout is given up; every failure is a
:class:`~gcs_planner.errors.LinkError` whose message says what the vehicle answered (a refusal:
:class:`~gcs_planner.errors.UploadRefused`). An upload is only reported done after the mission
has been read back and found equal to what was sent; a read-back that cannot be completed is a
:class:`ReadBackError` ("unknown"), never "it differs".

The client paces itself to the link (:mod:`gcs_planner.link.pacing`): it reads the RADIO_STATUS
a telemetry radio writes to it as ArduPilot does, sends no resend while the first copy can still
be in the channel, and sizes the download's outstanding requests to what the link delivers.

Missions can also travel by MAVLink FTP (:mod:`gcs_planner.link.ftp`,
:mod:`gcs_planner.link.mission_ftp`): ``transfer="auto"`` (the default, the library's as the
command line's) writes and reads ``@MISSION/mission.dat`` when the vehicle sets
MAV_PROTOCOL_CAPABILITY_FTP and its autopilot serves the mission as a file, and falls back to
the mission protocol when the vehicle has no such file or keeps it busy; ``"ftp"`` and
``"mission"`` force one. The read-back goes the way the upload went, with the same verdicts
(differs / could not read it back). An upload by MAVFTP is verified, by default
(``verify="crc"``), by the vehicle's CRC-32 of the mission file it serves, which costs four
small exchanges instead of the file's burst read (ArduPilot paces that to a third of the
serial rate); ``verify="read"`` always reads it back.
"""

from __future__ import annotations

from collections.abc import Sequence

from gcs_planner.errors import LinkError
from gcs_planner.link import mission_commands
from gcs_planner.link.mission_download import MAX_WINDOW, REORDER_SLACK
from gcs_planner.link.mission_download import download as download_mission
from gcs_planner.link.mission_upload import MissionUpload
from gcs_planner.link.outcome import ReadBackError, UploadReport
from gcs_planner.link.protocol import Tolerance
from gcs_planner.link.session import (
    DOWNLOAD_WINDOW,
    MIN_RESEND_S,
    TRANSFERS,
    VERIFIES,
    ProgressFactory,
    Vehicle,
    VehicleSession,
)
from gcs_planner.link.verified_upload import upload_verified as upload_and_verify
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

__all__ = [
    "DOWNLOAD_WINDOW",
    "MAX_WINDOW",
    "MIN_RESEND_S",
    "REORDER_SLACK",
    "TRANSFERS",
    "VERIFIES",
    "MissionClient",
    "ProgressFactory",
    "ReadBackError",
    "UploadReport",
    "Vehicle",
]


class MissionClient(VehicleSession):
    """Mission transfers with one vehicle over a :class:`~gcs_planner.link.connection.Link`.

    ``target_system`` / ``target_component`` pin the vehicle; left None they are learnt from the
    first vehicle heartbeat (:meth:`connect`). Messages from any other system or component are
    ignored, so a second vehicle or ground station on the link cannot confuse a transfer.
    """

    def upload(
        self, items: Sequence[MissionItem], mission_type: int = MAV_MISSION_TYPE_MISSION
    ) -> None:
        """Send ``items`` (MISSION_COUNT, then each requested item, until MISSION_ACK), as
        :mod:`~gcs_planner.link.mission_upload` describes.

        When every item was sent but the final acknowledgement never came, or came as an
        error to a resent last item, whether the vehicle stored the mission is unknown: a
        :class:`LinkError` says so. :meth:`upload_verified` reads the mission back instead.
        """
        outcome = MissionUpload(self, items, mission_type).run()
        if outcome.unconfirmed:
            raise LinkError(
                f"every item was sent but {outcome.reason}: whether the vehicle holds the "
                "mission is unknown (run `gcs-planner download` to see)"
            )

    def download(
        self, mission_type: int = MAV_MISSION_TYPE_MISSION, *, validate: bool = True
    ) -> list[MissionItem]:
        """The vehicle's mission (MISSION_REQUEST_LIST, MISSION_COUNT, MISSION_REQUEST_INT for
        each item, one at a time where the autopilot serves them in sequence (PX4), several
        outstanding where it answers any (ArduPilot), then our MISSION_ACK; or its mission file
        by MAVFTP, checked by the vehicle's CRC), as :mod:`~gcs_planner.link.mission_download`
        describes. With ``validate`` (the default) an item no mission file may hold is a
        :class:`LinkError` naming its seq and field."""
        return download_mission(self, mission_type, validate=validate)

    def clear(self, mission_type: int = MAV_MISSION_TYPE_MISSION) -> None:
        """MISSION_CLEAR_ALL, confirmed by MISSION_ACK."""
        mission_commands.clear(self, mission_type)

    def set_current(self, seq: int) -> None:
        """Make ``seq`` the current item: MAV_CMD_DO_SET_MISSION_CURRENT, falling back to the
        older MISSION_SET_CURRENT; success is the MISSION_CURRENT the vehicle broadcasts."""
        mission_commands.set_current(self, seq)

    def check_loiter_parameter(self) -> None:
        """Raise a :class:`LinkError` naming the parameter when the vehicle has no loiter-radius
        parameter under its autopilot's name (autopilots stay silent about unknown names)."""
        mission_commands.check_loiter_parameter(self)

    def upload_verified(
        self,
        items: Sequence[MissionItem],
        *,
        loiter_radius: float | None = None,
        tolerance: Tolerance | None = None,
    ) -> UploadReport:
        """Upload, read back (or check the vehicle's CRC of its mission file) and compare;
        optionally set the loiter radius (confirmed).

        A read-back that differs from the upload in any item, or in the number of items, is a
        :class:`LinkError` listing the differences: never a success.
        """
        return upload_and_verify(self, items, loiter_radius=loiter_radius, tolerance=tolerance)
