"""An upload as the whole job: send the mission the way the session chose (MAVFTP or the
mission protocol), verify it by the vehicle's CRC of its mission file or by reading it back,
then set the loiter radius, confirmed.

An upload is only reported done after the vehicle was found to hold what was sent: a
read-back that differs from the upload in any item, or in the number of items, is a
:class:`~gcs_planner.errors.LinkError` listing the differences, and one that cannot be
completed a :class:`~gcs_planner.link.outcome.ReadBackError` ("unknown"), never a success.
A CRC that differs, or a vehicle that does not answer it, is not a verdict: the whole file is
read back and compared then.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.errors import LinkError
from gcs_planner.link.ftp import FtpError
from gcs_planner.link.mission_by_ftp import (
    crc_check,
    falls_back,
    read_back_file,
    upload_file,
    use_ftp,
)
from gcs_planner.link.mission_read_back import read_back
from gcs_planner.link.mission_upload import MissionUpload, numbered
from gcs_planner.link.outcome import Outcome, UploadReport
from gcs_planner.link.params import set_loiter_radius
from gcs_planner.link.protocol import Tolerance, mission_differences
from gcs_planner.link.session import VehicleSession
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem


def upload_verified(
    session: VehicleSession,
    items: Sequence[MissionItem],
    *,
    loiter_radius: float | None = None,
    tolerance: Tolerance | None = None,
) -> UploadReport:
    """Upload, verify, and optionally set the loiter radius (confirmed); the report."""
    start = time.perf_counter()
    session._target()
    retries_before = session.retry_count
    tol = tolerance or Tolerance()
    sent = numbered(items)
    outcome = _send(session, sent)
    uploaded = time.perf_counter()
    verify, crc_note = _verify(session, items, sent, tol, outcome)
    verified = time.perf_counter()
    if loiter_radius is not None:
        set_loiter_radius(
            session.link,
            session._target(),
            loiter_radius,
            session.autopilot().firmware,
            timeout=session.timeout,
            retries=session.retries,
        )
    return UploadReport(
        items=len(items),
        seconds=time.perf_counter() - start,
        upload_seconds=uploaded - start,
        verify_seconds=verified - uploaded,
        retries=session.retry_count - retries_before,
        unacknowledged=outcome.unconfirmed,
        transfer=session.transfer_used,
        verify=verify,
        crc_note=crc_note,
    )


def _send(session: VehicleSession, sent: Sequence[MissionItem]) -> Outcome:
    """Send the mission by MAVFTP when the session uses it (back to the mission protocol on
    the failures an automatic choice falls back on), else by the mission protocol; the way it
    went is left in ``session.transfer_used``."""
    session.transfer_used = "ftp" if use_ftp(session) else "mission"
    if session.transfer_used == "ftp":
        try:
            return upload_file(session, sent)
        except FtpError as exc:
            if not falls_back(session, exc):
                raise
            session.transfer_used = "mission"
    return MissionUpload(session, sent, MAV_MISSION_TYPE_MISSION).run()


def _verify(
    session: VehicleSession,
    items: Sequence[MissionItem],
    sent: Sequence[MissionItem],
    tol: Tolerance,
    outcome: Outcome,
) -> tuple[str, str]:
    """How the upload was verified ("crc" or "read") and why a CRC asked was not enough;
    a :class:`LinkError` listing the differences when the vehicle holds another mission. An
    unconfirmed upload is decided here: the same mission is a success, anything else is not."""
    verify, crc_note = "read", ""
    by_ftp = session.transfer_used == "ftp"
    if by_ftp and session.verify == "crc":
        crc_note = crc_check(session, sent)
        verify = "read" if crc_note else "crc"
    if verify == "crc":
        return verify, crc_note  # the vehicle serves, byte for byte, the file of the items sent
    acknowledged = not outcome.unconfirmed
    if by_ftp:
        got = read_back_file(session, acknowledged=acknowledged)
    else:
        got = read_back(session, sent, tol, acknowledged=acknowledged)
    skip_home = keeps_home_item(session.firmware)
    diffs = mission_differences(list(items), got, skip_home=skip_home, tol=tol)
    if diffs:
        more = f"; and {len(diffs) - 5} more" if len(diffs) > 5 else ""
        shown = "; ".join(diffs[:5]) + more
        why = f" (every item was sent but {outcome.reason})" if outcome.unconfirmed else ""
        raise LinkError(f"the mission read back differs from the upload{why}: {shown}")
    return verify, crc_note
