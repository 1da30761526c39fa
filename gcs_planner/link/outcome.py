"""What a mission transfer comes to: the result of an upload that did not fail, the report of a
verified upload, and the error of a read-back that could not be completed.

A transfer that fails raises a :class:`~gcs_planner.errors.LinkError` (a refusal:
:class:`~gcs_planner.errors.UploadRefused`); one that does not returns an :class:`Outcome`,
whose :class:`TransferResult` says whether the vehicle acknowledged it (MAVSDK's
``MissionRaw::Result`` names every ending; here the failures are error types and the result
names the two ways an upload can end without one).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from gcs_planner.errors import LinkError


class TransferResult(Enum):
    """How an upload ended, short of a failure."""

    # The vehicle's final answer said it stored what was sent (MISSION_ACK ACCEPTED, or an
    # FTP close it acknowledged).
    ACKNOWLEDGED = "acknowledged"
    # Every item was sent and the vehicle went quiet, or answered a resent last item with an
    # error: whether it stored the mission is for the read-back to say.
    UNCONFIRMED = "unconfirmed"


@dataclass(frozen=True)
class Outcome:
    """A transfer's result and, when it is UNCONFIRMED, why."""

    result: TransferResult
    reason: str = ""

    @property
    def unconfirmed(self) -> bool:
        return self.result is TransferResult.UNCONFIRMED


ACKNOWLEDGED = Outcome(TransferResult.ACKNOWLEDGED)


def unconfirmed(reason: str) -> Outcome:
    """The outcome of an upload whose end the vehicle never confirmed, and why."""
    return Outcome(TransferResult.UNCONFIRMED, reason)


@dataclass(frozen=True)
class UploadReport:
    items: int
    seconds: float
    upload_seconds: float
    verify_seconds: float
    retries: int
    # The vehicle's final MISSION_ACK never came (or came as an error to a resent last item, as
    # ArduPilot answers one): the read-back alone showed that it holds the mission.
    unacknowledged: bool = False
    transfer: str = "mission"  # "ftp" (MAVFTP, @MISSION/mission.dat) or "mission"
    # "crc": the vehicle's CRC of the mission file matched the items sent; "read": the mission
    # was read back and compared.
    verify: str = "read"
    # Why a CRC verification asked was not enough (the read-back decided then), else "".
    crc_note: str = ""


class ReadBackError(LinkError):
    """The read-back after an upload could not be completed: what the vehicle holds is unknown
    (never "it differs", which is a plain :class:`LinkError` listing the differences)."""
