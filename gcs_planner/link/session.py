"""One vehicle on a link: who answered, our heartbeat, only its messages received, and the waits
every mission transfer paces itself by.

A :class:`VehicleSession` is what each transfer (:mod:`~gcs_planner.link.mission_upload`,
:mod:`~gcs_planner.link.mission_download`, :mod:`~gcs_planner.link.mission_by_ftp`,
:mod:`~gcs_planner.link.mission_commands`) works through: the target's ids, the autopilot its
heartbeat names, the measured round trip and the local radio's reports, and the counters the
reports print. Messages from any other system or component are ignored, so a second vehicle or
ground station on the link cannot confuse a transfer.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from gcs_planner.aircraft.autopilot import AUTOPILOTS, DEFAULT_AUTOPILOT, Autopilot, autopilot_for
from gcs_planner.aircraft.profile import FIRMWARE_OF_AUTOPILOT
from gcs_planner.errors import LinkError
from gcs_planner.link.connection import Link, mavlink
from gcs_planner.link.pacing import RadioFlow
from gcs_planner.link.progress import Progress
from gcs_planner.link.protocol import DEFAULT_RETRIES, DEFAULT_TIMEOUT_S, ITEM_TIMEOUT_S
from gcs_planner.link.rtt import RoundTrip

# Requests outstanding at once when a download starts (MAVProxy keeps five); the window then
# follows the link (pacing.Window). The shortest wait before a resend however fast the link
# answers: consecutive resends of one thing past the fourth double their wait (RFC 6298's
# backoff) up to the protocol's default timeout, so a fade costs a few resends.
DOWNLOAD_WINDOW = 8
MIN_RESEND_S = 0.03
_NOT_VEHICLES = {mavlink.MAV_TYPE_GCS, mavlink.MAV_TYPE_GIMBAL, mavlink.MAV_TYPE_ADSB}
# How missions travel: MAVFTP where the vehicle offers @MISSION/mission.dat (ArduPilot, with
# MAV_PROTOCOL_CAPABILITY_FTP), the mission protocol otherwise; or either, by choice.
TRANSFERS = ("auto", "ftp", "mission")
# How an upload by MAVFTP is verified: the vehicle's CRC of the file (a full read-back when it
# differs or is not answered), or always the full read-back.
VERIFIES = ("crc", "read")

ProgressFactory = Callable[[str, int], Progress]


def serves_mission_file(firmware: str | None) -> bool:
    """Whether the autopilot named ``firmware`` serves its mission as @MISSION/mission.dat;
    False for one without a record (a generic autopilot, or none heard yet)."""
    ap = AUTOPILOTS.get(firmware or "")
    return ap is not None and ap.protocol is not None and ap.protocol.serves_mission_file


@dataclass(frozen=True)
class Vehicle:
    """Who answered: system and component ids, and the firmware its heartbeat names."""

    system: int
    component: int
    autopilot: int
    firmware: str  # an autopilot's name (AUTOPILOTS) or "generic"


class VehicleSession:
    """The link to one vehicle, as every mission transfer with it sees it.

    ``target_system`` / ``target_component`` pin the vehicle; left None they are learnt from the
    first vehicle heartbeat (:meth:`connect`). ``transfer`` (:data:`TRANSFERS`) says how
    missions travel, ``verify`` (:data:`VERIFIES`) how an upload by MAVFTP is checked.
    """

    def __init__(
        self,
        link: Link,
        *,
        target_system: int | None = None,
        target_component: int | None = None,
        firmware: str | None = None,
        timeout: float = DEFAULT_TIMEOUT_S,
        item_timeout: float = ITEM_TIMEOUT_S,
        retries: int = DEFAULT_RETRIES,
        progress: ProgressFactory | None = None,
        window: int = DOWNLOAD_WINDOW,
        transfer: str = "auto",
        verify: str = "crc",
    ) -> None:
        if transfer not in TRANSFERS:
            raise LinkError(f"unknown transfer {transfer!r}: expected one of {TRANSFERS}")
        if verify not in VERIFIES:
            raise LinkError(f"unknown verification {verify!r}: expected one of {VERIFIES}")
        self.transfer = transfer
        self.verify = verify
        self.capabilities: int | None = None  # AUTOPILOT_VERSION's, once answered
        self._capabilities_asked: float | None = None  # when they were first asked
        self._capabilities_asked_last = 0.0
        self.transfer_used = "mission"  # how the last upload or download went
        if firmware is not None and firmware not in AUTOPILOTS:
            known = tuple(AUTOPILOTS)
            raise LinkError(f"unknown firmware {firmware!r}: expected one of {known}")
        self.link = link
        self.mav = link.mav
        self.target_system = target_system
        self.target_component = target_component
        self.firmware = firmware
        self.timeout = timeout
        self.item_timeout = item_timeout
        self.retries = retries
        self.progress: ProgressFactory = progress or (
            lambda label, total: Progress(label, total, enabled=False)
        )
        self.retry_count = 0  # resends done so far, for reports
        # Downloads: answers to an item already held (its resend was not needed: the first
        # answer was late, not lost), and of those the ones resent while a request asked
        # before it was still unanswered (on an in-order link its answer was behind that one's:
        # asked twice while its answer could still come).
        self.late_answers = 0
        self.hasty_resends = 0
        if window < 1:
            raise LinkError("the download window must be at least 1 request")
        self.window = window
        # Resends wait the measured round trip (RFC 6298), from the specification's item
        # timeout until there is a sample, up to the protocol's timeout (a radio's round trip
        # can be longer than the item timeout: a SiK pair at 64 kbit/s needs a TDM round
        # per request and answer).
        self._rtt = RoundTrip(floor=MIN_RESEND_S, ceiling=max(timeout, item_timeout))
        self._rtt_initial = item_timeout
        self.radio = RadioFlow()  # the local radio's RADIO_STATUS, when there is one
        self.window_used = window  # the download window at the end of the last download
        self._last_count: int | None = None  # the count the last download read
        self.vehicle: Vehicle | None = None
        self._last_gcs_heartbeat = 0.0
        # Whoever reads the link (a parameter read too) hands the vehicle's AUTOPILOT_VERSION
        # here, so the answer to the question asked at connect is not lost to another reader.
        link.watchers.append(self._watch)

    # Who answered -----------------------------------------------------------------------------
    def _send_heartbeat(self) -> None:
        self.link.send(
            self.mav.heartbeat_encode(
                mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, mavlink.MAV_STATE_ACTIVE
            )
        )
        self._last_gcs_heartbeat = time.monotonic()

    def connect(self, timeout: float = 10.0) -> Vehicle:
        """Wait for the vehicle's heartbeat, sending ours every second so that a vehicle
        listening on ``udpin`` learns where we are."""
        deadline = time.monotonic() + timeout
        while (remaining := deadline - time.monotonic()) > 0:
            if time.monotonic() - self._last_gcs_heartbeat >= 1.0:
                self._send_heartbeat()
            msg = self.link.recv(min(remaining, 0.25))
            if msg is None or not self._is_target_heartbeat(msg):
                continue
            self.target_system = msg.get_srcSystem()
            self.target_component = msg.get_srcComponent()
            flavour = FIRMWARE_OF_AUTOPILOT.get(msg.autopilot, "generic")
            if self.firmware is None:
                self.firmware = flavour
            self.vehicle = Vehicle(
                self.target_system, self.target_component, msg.autopilot, self.firmware
            )
            if self._wants_capabilities():
                # Asked now, answered while the command does what it does before the transfer.
                self._ask_capabilities()
            return self.vehicle
        raise self._no_heartbeat(timeout)

    def _is_target_heartbeat(self, msg: Any) -> bool:
        """A vehicle's heartbeat (not a ground station's, a gimbal's or an ADS-B receiver's),
        from the pinned ids when there are any."""
        if msg.get_type() != "HEARTBEAT" or msg.type in _NOT_VEHICLES:
            return False
        if msg.autopilot == mavlink.MAV_AUTOPILOT_INVALID:
            return False
        if self.target_system is not None and msg.get_srcSystem() != self.target_system:
            return False
        return self.target_component is None or msg.get_srcComponent() == self.target_component

    def _no_heartbeat(self, timeout: float) -> LinkError:
        if self.link.refused_signature:
            return LinkError(
                f"refused {self.link.refused_signature} message(s) from the other end: they "
                "are unsigned or signed with another key (check --signing-key)"
            )
        if self.link.refused_datagrams:
            return LinkError(
                f"no vehicle heartbeat on {self.link.connection} within {timeout:g} s: its "
                "host refused our datagrams (nothing listens on that port)"
            )
        return LinkError(f"no vehicle heartbeat on {self.link.connection} within {timeout:g} s")

    def _target(self) -> tuple[int, int]:
        if self.target_system is None or self.target_component is None:
            self.connect()
        return int(self.target_system), int(self.target_component)  # type: ignore[arg-type]

    def autopilot(self) -> Autopilot:
        """The record of the vehicle's autopilot; for a vehicle without one (a generic
        autopilot), the default autopilot's, whose parameter names it is asked by."""
        name = self.firmware if self.firmware in AUTOPILOTS else DEFAULT_AUTOPILOT
        return autopilot_for(name)

    def requests_in_sequence(self) -> bool:
        """Whether a download keeps one request out at a time: the autopilot's record says
        (PX4 ends a transfer asked out of order, ArduPilot answers any request); an autopilot
        without a record is asked one item at a time, as the specification's sequence shows."""
        ap = AUTOPILOTS.get(self.firmware or "")
        if ap is None or ap.protocol is None:
            return True
        return ap.protocol.requests_in_sequence

    def _wants_capabilities(self) -> bool:
        """Whether the transfer's choice needs AUTOPILOT_VERSION (``auto`` with an autopilot
        that serves its mission as a file); any other vehicle is not asked at all."""
        return self.transfer == "auto" and serves_mission_file(self.firmware)

    def _ask_capabilities(self) -> None:
        """Ask for AUTOPILOT_VERSION with MAV_CMD_REQUEST_MESSAGE and the older
        MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES at once: both autopilots answer either, so one
        answer lost on the way is not a silence."""
        ts, tc = self._target()
        self.link.send(self.mav.command_long_encode(ts, tc, mavlink.MAV_CMD_REQUEST_MESSAGE, 0,
                                                    mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION,
                                                    0, 0, 0, 0, 0, 0))  # fmt: skip
        self.link.send(self.mav.command_long_encode(ts, tc,
                                                    mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
                                                    0, 1, 0, 0, 0, 0, 0, 0))  # fmt: skip
        now = time.monotonic()
        if self._capabilities_asked is None:
            self._capabilities_asked = now
        self._capabilities_asked_last = now

    def _watch(self, msg: Any) -> None:
        if msg.get_type() == "AUTOPILOT_VERSION" and self._from_target(msg):
            self.capabilities = int(msg.capabilities)

    def _await_capabilities(self, until: float) -> bool:
        """Wait for the answer until ``until``, asking again each third of the protocol
        timeout (a lossy link loses questions and answers, a silent vehicle costs no more)."""
        while self.capabilities is None and (remaining := until - time.monotonic()) > 0:
            if time.monotonic() - self._capabilities_asked_last >= self.timeout / 3:
                self._ask_capabilities()
            self._recv(min(remaining, 0.1), {"AUTOPILOT_VERSION"}, None)
        return self.capabilities is not None

    def autopilot_capabilities(self) -> int:
        """AUTOPILOT_VERSION.capabilities, 0 when the vehicle says nothing (it offers no
        optional protocol then). Asked once a session, at connect when the transfer's choice
        needs it, so that the answer comes while the command does what it does first; the
        wait runs to the protocol timeout from when the question first went out, not from when
        the answer is needed, and is not repeated: a vehicle that never answers costs what is
        left of one timeout, and one whose every answer was lost only goes by the mission
        protocol."""
        if self.capabilities is not None:
            return self.capabilities
        if self._capabilities_asked is None:
            self._ask_capabilities()
        assert self._capabilities_asked is not None
        if not self._await_capabilities(self._capabilities_asked + self.timeout):
            self.capabilities = 0
        return int(self.capabilities)  # type: ignore[arg-type]

    # Its messages -----------------------------------------------------------------------------
    def _from_target(self, msg: Any) -> bool:
        if msg.get_srcSystem() != self.target_system:
            return False
        if msg.get_srcComponent() != self.target_component:
            return False
        # Messages addressed to someone else on a shared link are not ours to act on.
        ts = getattr(msg, "target_system", None)
        if ts not in (None, 0, self.mav.srcSystem):
            return False
        tc = getattr(msg, "target_component", None)
        return tc in (None, 0, self.mav.srcComponent)

    def _recv(self, timeout: float, types: set[str], mission_type: int | None) -> Any | None:
        """The next message of ``types`` from the target within ``timeout``; our heartbeat
        keeps going meanwhile."""
        deadline = time.monotonic() + timeout
        while (remaining := deadline - time.monotonic()) > 0:
            if time.monotonic() - self._last_gcs_heartbeat >= 1.0:
                self._send_heartbeat()
            msg = self.link.recv(min(remaining, 0.5))
            if msg is None:
                continue
            if self.radio.observe(msg):
                continue  # our radio's report: read here, never a transfer's message
            if msg.get_type() not in types or not self._from_target(msg):
                continue
            if mission_type is not None and getattr(msg, "mission_type", 0) != mission_type:
                continue
            return msg
        return None

    def signing_hint(self) -> str:
        """What signing may have to do with a silence, in words ("" when nothing): a vehicle
        heard signing while we do not, or frames of it refused for their signature."""
        if self.link.peer_signed and not self.link.signed:
            return (
                " (the vehicle signs its messages and ignores unsigned ones: give its key "
                "with --signing-key)"
            )
        if self.link.refused_signature:
            return f" ({self.link.refused_signature} message(s) refused: unsigned or another key)"
        return ""

    def _give_up(self, what: str) -> LinkError:
        extra = self.signing_hint()
        return LinkError(f"{what}: no answer after {self.retries + 1} attempts{extra}")

    def _cancel_transfer(self, mission_type: int) -> None:
        """MISSION_ACK OPERATION_CANCELLED: a transfer we did not start (a late duplicate of an
        old MISSION_COUNT put the vehicle in receive mode) or one of ours that failed ends as
        the specification allows, so the vehicle returns idle rather than waiting out its
        timeout (PX4 honours the cancel; to a vehicle not receiving from us it means
        nothing)."""
        ts, tc = self._target()
        self.link.send(
            self.mav.mission_ack_encode(
                ts, tc, mavlink.MAV_MISSION_OPERATION_CANCELLED, mission_type
            )
        )

    # The pace ---------------------------------------------------------------------------------
    def _resend_wait(self, attempts: int) -> float:
        """How long to wait for an answer before sending again, after ``attempts`` resends in
        a row of the same thing: the round-trip timeout (the item timeout before any sample),
        doubled per resend from the fifth on, at most the protocol timeout, plus the slowdown
        the local radio's reports call for. The first four go at the round trip's pace: on a
        link that loses frames at random (loopback at 20 % each way, 36 % of exchanges fail)
        a few losses in a row are common and say nothing of the channel; more in a row are a
        fade or a flood, where a copy sent sooner would only follow the last one into the
        same hole or queue."""
        base = self._rtt.timeout if self._rtt.srtt is not None else self._rtt_initial
        doublings = min(max(0, attempts - 4), 8)
        wait = min(max(base, self._rtt.floor) * (2**doublings), self.timeout)
        return max(wait, base) + self.radio.extra_wait()

    def _stall_limit(self) -> float:
        """Seconds without progress after which a transfer is given up: the specification's
        retries of its default timeout. Resends within it go at the round-trip's pace."""
        return (self.retries + 1) * self.timeout
