"""The read-back after an upload by the mission protocol: the mission downloaded again, resumed
across attempts, and a failure said as what it is ("could not read it back", never "it
differs" unless what was read differs).
"""

from __future__ import annotations

from collections.abc import Sequence

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.errors import LinkError
from gcs_planner.link.connection import mavlink
from gcs_planner.link.mission_download import LEFTOVER_ACKS, MissionDownload
from gcs_planner.link.outcome import ReadBackError
from gcs_planner.link.protocol import Tolerance, item_differences
from gcs_planner.link.session import VehicleSession
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

# Late copies of our items reach an ArduPilot no longer receiving, which answers each with
# MAV_MISSION_ERROR: left over from the upload, not a refusal. On an in-order link they all come
# before the read-back's MISSION_COUNT; one after it ends the transfer (mission_download.py).
_AFTER_UPLOAD = mavlink.MAV_MISSION_ERROR


def read_back(
    session: VehicleSession,
    sent: Sequence[MissionItem],
    tol: Tolerance,
    *,
    acknowledged: bool = True,
    attempts: int = 3,
) -> list[MissionItem]:
    """The mission just uploaded, read back. A read-back that fails is said as such: "could
    not read it back" is a :class:`ReadBackError`, never "it differs". Each attempt resumes
    where the last one stopped where the autopilot answers requests in any order (the items
    read stay read), so a link that drops out for a while costs the time it is out, not the
    whole read-back again."""
    got: dict[int, MissionItem] = {}
    expect: int | None = None
    session._last_count = None
    leftovers = (*LEFTOVER_ACKS, _AFTER_UPLOAD)
    for attempt in range(attempts):
        try:
            return MissionDownload(session, got, MAV_MISSION_TYPE_MISSION, expect, leftovers).run()
        except LinkError as exc:
            expect = session._last_count
            if attempt < attempts - 1:
                continue
            raise _read_back_failed(session, sent, got, expect, tol, exc, acknowledged) from None
    raise AssertionError("unreachable")


def _read_back_failed(
    session: VehicleSession,
    sent: Sequence[MissionItem],
    got: dict[int, MissionItem],
    expect: int | None,
    tol: Tolerance,
    exc: LinkError,
    acknowledged: bool,
) -> LinkError:
    """The error of a read-back whose last attempt failed: what was read is compared all the
    same (a difference is a difference); otherwise what the vehicle holds is unknown."""
    wrong = _partial_differences(session, sent, got, tol)
    said = (
        "the vehicle acknowledged the whole upload (MISSION_ACK ACCEPTED)"
        if acknowledged
        else "the vehicle never acknowledged the end of the upload"
    )
    read = (
        f"{len(got)} of {expect} items were read back"
        if expect is not None
        else "not even the item count was read back"
    )
    if wrong:
        return LinkError(
            f"the mission read back differs from the upload ({read} before the "
            f"link failed): {'; '.join(wrong[:5])}"
        )
    return ReadBackError(
        f"{said} but it could not be read back to verify it: {exc}. {read}"
        f"{', all as uploaded' if got and expect is not None else ''}; the "
        "read-back failed, so whether the vehicle holds this mission is unknown: "
        "run `gcs-planner download` to check"
    )


def _partial_differences(
    session: VehicleSession,
    sent: Sequence[MissionItem],
    got: dict[int, MissionItem],
    tol: Tolerance,
) -> list[str]:
    """The differences between the items read back so far and the ones sent."""
    out: list[str] = []
    for seq in sorted(got):
        if seq >= len(sent):
            out.append(f"item {seq}: read back, but only {len(sent)} items were uploaded")
        elif not (seq == 0 and keeps_home_item(session.firmware)):
            out.extend(f"item {seq}: {d}" for d in item_differences(sent[seq], got[seq], tol))
    return out
