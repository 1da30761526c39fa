"""The ground-station side of the MAVLink mission protocol: upload, download, clear, set current.

One object per vehicle. Every wait has a deadline (1.5 s by default; for a single item the
measured round trip, 0.25 s as the specification recommends until there is one) and a transfer
that makes no progress for its retries of the timeout is given up; every failure is a
:class:`~gcs_planner.errors.LinkError` whose message says what the vehicle answered. An upload is
only reported done after the mission has been read back and found equal to what was sent; a
read-back that cannot be completed is a :class:`ReadBackError` ("unknown"), never "it differs".

The client paces itself to the link (:mod:`gcs_planner.link.pacing`): it reads the RADIO_STATUS
a telemetry radio writes to it as ArduPilot does, sends no resend while the first copy can still
be in the channel, and sizes the download's outstanding requests to what the link delivers.

Missions can also travel by MAVLink FTP (:mod:`gcs_planner.link.ftp`,
:mod:`gcs_planner.link.mission_ftp`): ``transfer="auto"`` writes and reads
``@MISSION/mission.dat`` when the vehicle's AUTOPILOT_VERSION sets MAV_PROTOCOL_CAPABILITY_FTP
and it runs ArduPilot (PX4 sets the bit but serves no @MISSION), and falls back to the mission
protocol when the vehicle answers that it has no such file, or keeps the file busy (another
ground station's upload holds it); ``"ftp"`` and ``"mission"`` force
one; ``auto`` is the default, the library's as the command line's. The read-back
goes the way the upload went, with the same verdicts (differs / could not read it back).

An upload by MAVFTP is verified, by default (``verify="crc"``), by the vehicle's CRC-32 of
the mission file it serves (CalcFileCRC32): ArduPilot builds that file from the mission it
stores (AP_Filesystem_Mission::read through AP_Mission::get_item), not from the bytes it was
sent, so a CRC equal to that of the file predicted for the items sent
(:func:`~gcs_planner.link.mission_ftp.stored_file`, with the vehicle's own home read from
the file's first item) says it stores them, every byte. A CRC that differs, or a vehicle
that does not answer it, is not a verdict: the whole file is read back and compared, as with
``verify="read"``. The CRC costs four small exchanges instead of the file's burst read,
which ArduPilot paces to a third of the serial rate.
"""

from __future__ import annotations

import itertools
import struct
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.aircraft.profile import FIRMWARE_OF_AUTOPILOT, FIRMWARES, LOITER_RADIUS_PARAM
from gcs_planner.errors import InputError, LinkError, UploadRefused
from gcs_planner.link.connection import Link, mavlink
from gcs_planner.link.ftp import (
    FILE_NOT_FOUND,
    NAK,
    UNKNOWN_COMMAND,
    FtpBusy,
    FtpClient,
    FtpError,
    FtpQuiet,
)
from gcs_planner.link.mission_ftp import (
    HEADER,
    ITEM,
    MAGIC,
    MISSION_PATH,
    crc32,
    decode_mission,
    encode_mission,
    mission_length,
    stored_file,
    stored_item_bytes,
    without_leftovers,
)
from gcs_planner.link.pacing import RadioFlow, Window
from gcs_planner.link.params import read_parameter, set_loiter_radius
from gcs_planner.link.progress import Progress
from gcs_planner.link.protocol import (
    DEFAULT_RETRIES,
    DEFAULT_TIMEOUT_S,
    ITEM_TIMEOUT_S,
    Tolerance,
    describe_result,
    item_differences,
    item_from_message,
    item_to_message,
    mission_differences,
)
from gcs_planner.link.rtt import RoundTrip
from gcs_planner.link.validate import item_problem
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

# Requests outstanding at once when a download starts (MAVProxy keeps five); the window then
# follows the link (pacing.Window). The shortest wait before a resend however fast the link
# answers, and the most: consecutive resends of one thing past the fourth double their wait
# (RFC 6298's backoff) up to the protocol's default timeout: a fade costs a few resends.
DOWNLOAD_WINDOW = 8
MAX_WINDOW = 32
MIN_RESEND_S = 0.03
# An answer that arrives after later ones overtook it is taken as lost after this many later
# answers (the links are in order; a radio or router reorders little): asked again at once.
REORDER_SLACK = 3
_LEFTOVER_ACKS = (mavlink.MAV_MISSION_ACCEPTED, mavlink.MAV_MISSION_INVALID_SEQUENCE)
_AFTER_UPLOAD = mavlink.MAV_MISSION_ERROR
# Refusals of a MISSION_COUNT that mean "busy with another transfer": ArduPilot DENIED, PX4
# ERROR ("Mission upload busy"), and a cancel of the transfer it was in that crossed our count.
_BUSY = (
    mavlink.MAV_MISSION_DENIED,
    mavlink.MAV_MISSION_ERROR,
    mavlink.MAV_MISSION_OPERATION_CANCELLED,
)
_COMMAND_OK = (mavlink.MAV_RESULT_ACCEPTED, mavlink.MAV_RESULT_IN_PROGRESS)
_NOT_VEHICLES = {mavlink.MAV_TYPE_GCS, mavlink.MAV_TYPE_GIMBAL, mavlink.MAV_TYPE_ADSB}
# How missions travel: MAVFTP where the vehicle offers @MISSION/mission.dat (ArduPilot, with
# MAV_PROTOCOL_CAPABILITY_FTP), the mission protocol otherwise; or either, by choice.
TRANSFERS = ("auto", "ftp", "mission")
# How an upload by MAVFTP is verified: the vehicle's CRC of the file (a full read-back when it
# differs or is not answered), or always the full read-back.
VERIFIES = ("crc", "read")
# An open refused with these says the vehicle has no such file or no FTP: auto falls back.
_NO_MISSION_FILE = (FILE_NOT_FOUND, UNKNOWN_COMMAND)


def _span(first: int, last: int) -> str:
    return str(first) if first == last else f"{first}..{last}"


@dataclass(frozen=True)
class Vehicle:
    """Who answered: system and component ids, and the firmware its heartbeat names."""

    system: int
    component: int
    autopilot: int
    firmware: str  # "ardupilot", "px4" or "generic"


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


class _Unconfirmed(Exception):
    """Every item was sent and the vehicle went quiet, or answered a resent last item with an
    error: whether it stored the mission is for the read-back to say."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


ProgressFactory = Callable[[str, int], Progress]


class MissionClient:
    """Mission transfers with one vehicle over a :class:`Link`.

    ``target_system`` / ``target_component`` pin the vehicle; left None they are learnt from the
    first vehicle heartbeat (:meth:`connect`). Messages from any other system or component are
    ignored, so a second vehicle or ground station on the link cannot confuse a transfer.
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
        self.capabilities: int | None = None  # AUTOPILOT_VERSION's, once asked
        self.transfer_used = "mission"  # how the last upload or download went
        if firmware is not None and firmware not in FIRMWARES:
            raise LinkError(f"unknown firmware {firmware!r}: expected one of {FIRMWARES}")
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
        # can be longer than the item timeout: a SiK pair at 64 kbit/s needs a TDM round,
        # about 0.24 s, per request and answer).
        self._rtt = RoundTrip(floor=MIN_RESEND_S, ceiling=max(timeout, item_timeout))
        self._rtt_initial = item_timeout
        self.radio = RadioFlow()  # the local radio's RADIO_STATUS, when there is one
        self.window_used = window  # the download window at the end of the last download
        self._last_count: int | None = None  # the count the last download read
        self.vehicle: Vehicle | None = None
        self._last_gcs_heartbeat = 0.0

    # Connection -------------------------------------------------------------------------------
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
            if msg is None or msg.get_type() != "HEARTBEAT" or msg.type in _NOT_VEHICLES:
                continue
            if msg.autopilot == mavlink.MAV_AUTOPILOT_INVALID:
                continue
            if self.target_system is not None and msg.get_srcSystem() != self.target_system:
                continue
            if (
                self.target_component is not None
                and msg.get_srcComponent() != self.target_component
            ):
                continue
            self.target_system = msg.get_srcSystem()
            self.target_component = msg.get_srcComponent()
            flavour = FIRMWARE_OF_AUTOPILOT.get(msg.autopilot, "generic")
            if self.firmware is None:
                self.firmware = flavour
            self.vehicle = Vehicle(
                self.target_system, self.target_component, msg.autopilot, self.firmware
            )
            return self.vehicle
        if self.link.refused_signature:
            raise LinkError(
                f"refused {self.link.refused_signature} message(s) from the other end: they "
                "are unsigned or signed with another key (check --signing-key)"
            )
        if self.link.refused_datagrams:
            raise LinkError(
                f"no vehicle heartbeat on {self.link.connection} within {timeout:g} s: its "
                "host refused our datagrams (nothing listens on that port)"
            )
        raise LinkError(f"no vehicle heartbeat on {self.link.connection} within {timeout:g} s")

    def _target(self) -> tuple[int, int]:
        if self.target_system is None or self.target_component is None:
            self.connect()
        return int(self.target_system), int(self.target_component)  # type: ignore[arg-type]

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

    def _give_up(self, what: str) -> LinkError:
        extra = ""
        if self.link.peer_signed and not self.link.signed:
            extra = (
                " (the vehicle signs its messages and ignores unsigned ones: give its key "
                "with --signing-key)"
            )
        elif self.link.refused_signature:
            extra = f" ({self.link.refused_signature} message(s) refused: unsigned or another key)"
        return LinkError(f"{what}: no answer after {self.retries + 1} attempts{extra}")

    def _cancel_stray(self, msg: Any, mission_type: int) -> None:
        """A request we did not start (a late duplicate of an old MISSION_COUNT put the vehicle
        in receive mode): cancel it as the specification allows, so the vehicle returns idle."""
        ts, tc = self._target()
        self.link.send(
            self.mav.mission_ack_encode(
                ts, tc, mavlink.MAV_MISSION_OPERATION_CANCELLED, mission_type
            )
        )

    # Upload -----------------------------------------------------------------------------------
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

    def upload(
        self, items: Sequence[MissionItem], mission_type: int = MAV_MISSION_TYPE_MISSION
    ) -> None:
        """Send ``items`` (MISSION_COUNT, then each requested item, until MISSION_ACK).

        Answers MISSION_REQUEST and MISSION_REQUEST_INT alike, always with MISSION_ITEM_INT.
        An item that gets no answer is sent again after the round-trip timeout, doubled for
        each resend in a row, plus the slowdown the local radio's RADIO_STATUS calls for; no
        resend goes while that radio says its buffer is nearly full (the first copy is still
        in it). A request for an item sent less than a round-trip timeout ago crossed that
        copy and is not answered again. An INVALID_SEQUENCE acknowledgement of a resent item
        says the vehicle already had it and its request for the next one was lost: the next
        one is sent without waiting for the vehicle's own re-request (ArduPilot's comes only
        after a second). Any other error result ends the transfer with that result in words.

        A vehicle still inside an earlier upload of ours (one that died mid-transfer) is
        restarted: requests it makes for that transfer before asking for item 0 of this one are
        not ours and are ignored, and a MISSION_COUNT it refuses as busy is followed by a
        MISSION_ACK OPERATION_CANCELLED and the count again, once (PX4 restarts only after a
        cancel; ArduPilot restarts on the count of the same ids).

        When every item was sent but the final acknowledgement never came, or came as an
        error to a resent last item (ArduPilot, no longer receiving, answers any item with
        MAV_MISSION_ERROR), whether the vehicle stored the mission is unknown: a
        :class:`LinkError` says so. :meth:`upload_verified` reads the mission back instead.
        """
        try:
            self._upload(items, mission_type)
        except _Unconfirmed as exc:
            raise LinkError(
                f"every item was sent but {exc.reason}: whether the vehicle holds the mission "
                "is unknown (run `gcs-planner download` to see)"
            ) from None

    def _upload(self, items: Sequence[MissionItem], mission_type: int) -> None:
        ts, tc = self._target()
        items = [it.with_seq(i) if it.seq != i else it for i, it in enumerate(items)]
        self._check_packable(items, ts, tc)
        count = len(items)
        count_msg = self.mav.mission_count_encode(ts, tc, count, mission_type)
        self.link.send(count_msg)
        bar = self.progress("upload", count)
        requested: int | None = None  # the item last sent, answering a request
        sent_at = time.monotonic()
        resent = False
        attempts = 0  # resends in a row without progress, for the backoff
        copies: dict[int, float] = {}  # item -> when a copy of it last went out
        highest = -1  # the highest item the vehicle asked for
        sent_upto = -1  # the highest item sent, asked for or inferred
        last_progress = time.monotonic()
        cancelled_once = False  # a busy refusal of the count has been answered with a cancel
        last_ack: int | None = None  # the last MISSION_ACK the vehicle sent that we went past
        early_ack_waits = -1  # timeouts since an ACCEPTED came before the last item was sent
        stale: int | None = None  # a request of an earlier transfer, ignored
        all_sent = count == 0  # every item has gone out at least once

        def send_item(seq: int, now: float) -> None:
            copies[seq] = now
            self.link.send(item_to_message(self.mav, items[seq], ts, tc))

        try:
            while True:
                if requested is None:
                    wait = self.timeout * (2 ** min(attempts, 2)) + self.radio.extra_wait()
                else:
                    wait = self._resend_wait(attempts)
                msg = self._recv(
                    wait, {"MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK"}, mission_type
                )
                now = time.monotonic()
                if msg is None:
                    if early_ack_waits >= 0:
                        early_ack_waits += 1
                    if early_ack_waits > 2 or now - last_progress > self._stall_limit():
                        if all_sent and early_ack_waits < 0:
                            raise _Unconfirmed("no MISSION_ACK came for the last item")
                        raise self._upload_stalled(requested, sent_upto, count, last_ack, stale)
                    if self.radio.congested():
                        continue  # the radio's buffer still holds the first copy: no second
                    self.retry_count += 1
                    attempts += 1
                    resent, sent_at = True, now
                    if requested is None:
                        self.link.send(count_msg)
                    else:
                        send_item(requested, now)
                    continue
                if msg.get_type() == "MISSION_ACK":
                    if msg.type == mavlink.MAV_MISSION_ACCEPTED:
                        if count == 0 or sent_upto == count - 1:
                            return
                        if highest >= 0:
                            # Our transfer is under way and the vehicle says it is over: either
                            # a late copy of an earlier transfer's answer (a request follows)
                            # or the vehicle ended ours early (nothing follows).
                            last_ack = msg.type
                            early_ack_waits = max(early_ack_waits, 0)
                        continue  # before our first request: an earlier transfer's answer
                    if msg.type == mavlink.MAV_MISSION_INVALID_SEQUENCE:
                        last_ack = msg.type
                        # In reply to a resent item j: the vehicle has j (it would have taken it
                        # otherwise) and its request for j + 1 was lost. A wrong guess costs
                        # only a refusal; the vehicle's own re-request sets us right.
                        if resent and requested is not None and requested + 1 < count:
                            nxt = requested + 1
                            if now - copies.get(nxt, -1e9) < self._resend_wait(0):
                                continue  # a copy of it is already on its way
                            requested = nxt
                            attempts = 0  # progress: the vehicle has the item resent
                            sent_upto = max(sent_upto, requested)
                            all_sent = all_sent or sent_upto == count - 1
                            resent, sent_at = False, now
                            send_item(requested, now)
                        continue
                    if (
                        all_sent
                        and msg.type == mavlink.MAV_MISSION_ERROR
                        and requested == count - 1
                        and resent
                    ):
                        # ArduPilot's answer to an item when it is not receiving: the first
                        # copy of the last item ended the transfer and its ACK was lost, or the
                        # transfer failed; only the read-back can tell which.
                        raise _Unconfirmed(
                            "the vehicle answered the resent last item with MISSION_ACK "
                            f"{describe_result(msg.type)}"
                        )
                    if requested is None and not cancelled_once and msg.type in _BUSY:
                        # Refused before it asked for anything: most often it is still inside
                        # an earlier upload of ours that died. Cancel that one and count again.
                        cancelled_once = True
                        self._cancel_stray(msg, mission_type)
                        self.link.send(count_msg)
                        sent_at = last_progress = now
                        continue
                    where = "MISSION_COUNT" if requested is None else f"item {sent_upto}"
                    raise UploadRefused(
                        f"upload refused after {where}: MISSION_ACK {describe_result(msg.type)}"
                    )
                seq = int(msg.seq)
                if not 0 <= seq < count:
                    if highest < 0:
                        stale = seq
                        continue  # a request of an earlier, longer transfer
                    raise LinkError(f"the vehicle requested item {seq} of a {count}-item mission")
                if seq > sent_upto + 1:
                    if highest < 0:
                        # It has not asked for item 0 of this transfer yet: a re-request left
                        # over from an earlier one, which our count is about to restart.
                        stale = seq
                        continue
                    raise LinkError(
                        f"the vehicle requested item {seq} after item {sent_upto}: it skipped "
                        f"item{'s' if seq - sent_upto > 2 else ''} "
                        f"{_span(sent_upto + 1, seq - 1)}, which it was never sent (a vehicle "
                        "asks for every item in turn); the upload was cancelled"
                    )
                if requested is not None and seq == requested + 1 and not resent:
                    self._rtt.sample(now - sent_at)
                if seq > highest:
                    last_progress = now
                    early_ack_waits = -1
                    attempts = 0
                if seq <= highest and now - copies.get(seq, -1e9) < self._resend_wait(0):
                    # A re-request that crossed the copy we sent: that copy can still arrive,
                    # and a second one would only queue behind it on a slow link.
                    continue
                requested = seq
                highest = max(highest, seq)
                sent_upto = max(sent_upto, seq)
                all_sent = all_sent or sent_upto == count - 1
                resent, sent_at = False, now
                send_item(seq, now)
                bar.update(highest + 1)
        except LinkError:
            # Leave the vehicle idle rather than waiting out its upload timeout (PX4 honours
            # the cancel; to a vehicle not receiving from us it means nothing).
            self._cancel_upload(mission_type)
            raise
        finally:
            bar.close()

    def _check_packable(self, items: Sequence[MissionItem], ts: int, tc: int) -> None:
        """Refuse, before the count goes out, an item MISSION_ITEM_INT cannot carry (a latitude
        in degE7 given as degrees overflows its int32): the caller's input, named by item."""
        for item in items:
            try:
                item_to_message(self.mav, item, ts, tc).pack(self.mav)
            except (struct.error, OverflowError, ValueError, TypeError):
                problem = item_problem(item)
                reason = f"{problem.field}: {problem.reason}" if problem else "does not pack"
                raise InputError(
                    f"mission item {item.seq} cannot be sent in MISSION_ITEM_INT: {reason}"
                ) from None

    def _cancel_upload(self, mission_type: int) -> None:
        ts, tc = self._target()
        self.link.send(
            self.mav.mission_ack_encode(
                ts, tc, mavlink.MAV_MISSION_OPERATION_CANCELLED, mission_type
            )
        )

    def _upload_stalled(
        self,
        requested: int | None,
        sent_upto: int,
        count: int,
        last_ack: int | None,
        stale: int | None,
    ) -> LinkError:
        if last_ack == mavlink.MAV_MISSION_ACCEPTED:
            return LinkError(
                f"the vehicle ended the upload early, after item {sent_upto} of items 0.."
                f"{count - 1}, with MISSION_ACK {describe_result(last_ack)}, and asked for no "
                "more: what it holds is unknown (run `gcs-planner download` to see)"
            )
        where = "MISSION_COUNT" if requested is None else f"item {requested}"
        error = self._give_up(f"upload stalled after {where}")
        extra = ""
        if last_ack is not None:
            extra = f"; the vehicle's last answer was MISSION_ACK {describe_result(last_ack)}"
        elif requested is None and stale is not None:
            extra = (
                f"; the vehicle asked only for item {stale}, never for item 0: it did not "
                "restart its earlier transfer"
            )
        return LinkError(str(error) + extra)

    # Download ---------------------------------------------------------------------------------
    def download(
        self, mission_type: int = MAV_MISSION_TYPE_MISSION, *, validate: bool = True
    ) -> list[MissionItem]:
        """The vehicle's mission (MISSION_REQUEST_LIST, MISSION_COUNT, MISSION_REQUEST_INT for
        each item with several requests outstanding, as MAVProxy does, then our MISSION_ACK).

        How many requests are out at once follows the link (:class:`pacing.Window`: delivery
        rate times the shortest round trip), starting from ``window``; none is added while the
        local radio says its buffer is nearly full. A request is asked again when later items
        overtook its answer (the link is in order, so it was lost) or after the round-trip
        timeout, doubled for each time it was asked already: never while its first copy can
        still be in the channel.

        With ``validate`` (the default) an item no mission file may hold (validate.py: unknown
        frame or command, a position out of range or not set, a non-finite altitude or
        parameter) is a :class:`LinkError` naming its seq and field: what a vehicle sends is
        input like any other. The read-back after an upload compares instead."""
        mission: list[MissionItem] | None = None
        self.transfer_used = "mission"
        if mission_type == MAV_MISSION_TYPE_MISSION and self._use_ftp():
            self.transfer_used = "ftp"
            try:
                mission = self._ftp_read({})
            except FtpError as exc:
                if not self._fallback(exc):
                    raise
                self.transfer_used = "mission"
        if mission is None:
            mission = self._download_into({}, mission_type)
        if validate:
            for item in mission:
                problem = item_problem(item)
                if problem is not None:
                    raise LinkError(
                        f"the vehicle sent an invalid mission item: seq {item.seq}, field "
                        f"{problem.field!r}: {problem.reason}"
                    )
        return mission

    def _download_into(
        self,
        got: dict[int, MissionItem],
        mission_type: int,
        expect: int | None = None,
        leftovers: tuple[int, ...] = _LEFTOVER_ACKS,
    ) -> list[MissionItem]:
        """Download into ``got`` (items already there are not asked for again, so a read-back
        retried after a failure resumes). ``expect``: the count an earlier attempt read; a
        different one now means the mission changed and ``got`` is started afresh.
        ``leftovers``: the MISSION_ACK results taken as answers to an earlier transfer."""
        ts, tc = self._target()
        count = self._download_count(ts, tc, mission_type)
        if expect is not None and count != expect:
            got.clear()
        self._last_count = count
        sent: dict[int, tuple[float, int]] = {}  # seq -> (when last asked, times asked)
        ticket: dict[int, int] = {}  # seq -> the number of its last request, in sending order
        overtaken: dict[int, int] = {}  # seq -> answers to later requests that came first
        tickets = itertools.count()
        fixed = self.window == 1  # the classic client: one request at a time, always
        window = Window(self.window, low=1 if fixed else 2, high=1 if fixed else MAX_WINDOW)
        bar = self.progress("download", count)
        bar.update(len(got))
        last_progress = time.monotonic()
        missing = [seq for seq in range(count) if seq not in got]
        next_new = 0  # index into missing
        stalls = 0  # timeouts in a row with no answer: the backoff of the whole link
        behind: dict[int, bool] = {}  # seq -> resent while an earlier request was unanswered
        # The timer resends only once a receive has found nothing waiting: a process kept off
        # the CPU past the timer finds the answer it waited for already here, not lost.
        drained = False
        try:
            while len(got) < count:
                now = time.monotonic()
                congested = self.radio.congested()
                # Only the oldest request is timed (TCP's one retransmission timer): on an
                # in-order link every later answer waits behind its answer, so timing them
                # too would ask again for what is still on its way. The others are asked
                # again when later answers overtake theirs.
                oldest = min(sent, key=ticket.__getitem__, default=None)
                for seq, (when, asked) in list(sent.items()):
                    lost = overtaken[seq] >= REORDER_SLACK
                    due = seq == oldest and drained and now - when > self._resend_wait(stalls)
                    if not (lost or due) or congested:
                        continue
                    self.retry_count += 1
                    behind[seq] = any(ticket[o] < ticket[seq] for o in sent if o != seq)
                    window.lost()
                    sent[seq] = (now, asked + 1)
                    ticket[seq], overtaken[seq] = next(tickets), 0
                    self._request_item(ts, tc, seq, mission_type)
                    if due:
                        stalls += 1
                        # The timer restarts for what is still out, as TCP's does.
                        for other, (_, n) in sent.items():
                            if other != seq:
                                sent[other] = (now, n)
                while len(sent) < window.size and next_new < len(missing) and not congested:
                    seq = missing[next_new]
                    next_new += 1
                    if seq in got:
                        continue
                    sent[seq] = (now, 1)
                    ticket[seq], overtaken[seq] = next(tickets), 0
                    self._request_item(ts, tc, seq, mission_type)
                oldest = min(sent, key=ticket.__getitem__, default=None)
                wait = (
                    self._resend_wait(stalls) - (now - sent[oldest][0])
                    if oldest is not None
                    else self._resend_wait(0)
                )
                msg = self._recv(
                    max(wait, 0.005),
                    {"MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_ACK"},
                    mission_type,
                )
                now = time.monotonic()
                drained = msg is None
                if msg is None:
                    if now - last_progress > self._stall_limit():
                        first = min(set(range(count)) - set(got))
                        raise self._give_up(f"download: item {first}")
                    continue
                if msg.get_type() == "MISSION_ACK":
                    if msg.type in leftovers:
                        continue  # leftovers of an earlier transfer
                    raise LinkError(f"download refused: {describe_result(msg.type)}")
                seq = int(msg.seq)
                if seq in got:
                    # The answer to a request asked again (the first answer was late, not
                    # lost), or the resend's after it.
                    self.late_answers += 1
                    self.hasty_resends += behind.get(seq, False)
                    continue
                if not 0 <= seq < count:
                    continue  # not an item of this mission
                limited = len(sent) >= window.size
                asked = sent.pop(seq, None)
                mine = ticket.pop(seq, None)
                overtaken.pop(seq, None)
                if mine is not None:
                    for other, theirs in ticket.items():
                        if theirs < mine:
                            overtaken[other] += 1
                if asked is not None and asked[1] == 1:
                    # Karn's rule: a round trip only from a request asked once.
                    self._rtt.sample(now - asked[0])
                    window.rtt(now - asked[0])
                window.delivered(now, limited)
                stalls = 0
                got[seq] = item_from_message(msg)
                last_progress = now
                bar.update(len(got))
        finally:
            bar.close()
            self.window_used = window.size
        done = self.mav.mission_ack_encode(ts, tc, mavlink.MAV_MISSION_ACCEPTED, mission_type)
        self.link.send(done)
        return [got[seq] for seq in range(count)]

    def _request_item(self, ts: int, tc: int, seq: int, mission_type: int) -> None:
        self.link.send(self.mav.mission_request_int_encode(ts, tc, seq, mission_type))

    def _download_count(self, ts: int, tc: int, mission_type: int) -> int:
        request_list = self.mav.mission_request_list_encode(ts, tc, mission_type)
        self.link.send(request_list)
        attempts = 0
        while True:
            msg = self._recv(
                self.timeout,
                {"MISSION_COUNT", "MISSION_ACK", "MISSION_REQUEST", "MISSION_REQUEST_INT"},
                mission_type,
            )
            if msg is None or (
                msg.get_type() == "MISSION_ACK" and msg.type == mavlink.MAV_MISSION_DENIED
            ):
                # DENIED: the vehicle is busy receiving; it will time out or be cancelled.
                attempts += 1
                if attempts > self.retries:
                    if msg is not None:
                        raise LinkError(f"download refused: {describe_result(msg.type)}")
                    raise self._give_up("download: MISSION_REQUEST_LIST")
                self.retry_count += 1
                if msg is not None:
                    time.sleep(min(self.timeout, 0.2))
                self.link.send(request_list)
                continue
            kind = msg.get_type()
            if kind == "MISSION_COUNT":
                return int(msg.count)
            if kind == "MISSION_ACK":
                if msg.type in (mavlink.MAV_MISSION_ACCEPTED, mavlink.MAV_MISSION_INVALID_SEQUENCE):
                    continue  # leftovers of an earlier transfer
                raise LinkError(f"download refused: {describe_result(msg.type)}")
            self._cancel_stray(msg, mission_type)

    # Clear and set current --------------------------------------------------------------------
    def clear(self, mission_type: int = MAV_MISSION_TYPE_MISSION) -> None:
        """MISSION_CLEAR_ALL, confirmed by MISSION_ACK."""
        ts, tc = self._target()
        msg_out = self.mav.mission_clear_all_encode(ts, tc, mission_type)
        for _ in range(self.retries + 1):
            self.link.send(msg_out)
            msg = self._recv(self.timeout, {"MISSION_ACK"}, mission_type)
            if msg is None:
                self.retry_count += 1
                continue
            if msg.type == mavlink.MAV_MISSION_ACCEPTED:
                return
            raise LinkError(f"clear refused: {describe_result(msg.type)}")
        raise self._give_up("clear: MISSION_CLEAR_ALL")

    def set_current(self, seq: int) -> None:
        """Make ``seq`` the current item: MAV_CMD_DO_SET_MISSION_CURRENT, falling back to the
        older MISSION_SET_CURRENT; success is the MISSION_CURRENT the vehicle broadcasts."""
        ts, tc = self._target()
        command = self.mav.command_long_encode(
            ts, tc, mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, 0, seq, 0, 0, 0, 0, 0, 0
        )
        legacy = self.mav.mission_set_current_encode(ts, tc, seq)
        use_legacy = False
        for _ in range(self.retries + 1):
            self.link.send(legacy if use_legacy else command)
            deadline = time.monotonic() + self.timeout
            while (remaining := deadline - time.monotonic()) > 0:
                msg = self._recv(remaining, {"MISSION_CURRENT", "COMMAND_ACK", "STATUSTEXT"}, None)
                if msg is None:
                    break
                kind = msg.get_type()
                if kind == "MISSION_CURRENT" and int(msg.seq) == seq:
                    return
                if kind == "COMMAND_ACK" and msg.command == mavlink.MAV_CMD_DO_SET_MISSION_CURRENT:
                    if msg.result == mavlink.MAV_RESULT_UNSUPPORTED:
                        use_legacy = True
                        break
                    if msg.result not in _COMMAND_OK:
                        raise LinkError(f"the vehicle refused to make item {seq} current")
                if kind == "STATUSTEXT" and "current" in str(msg.text).lower():
                    raise LinkError(f"the vehicle refused to make item {seq} current: {msg.text}")
            self.retry_count += 1
        raise self._give_up(f"set current item {seq}")

    def _read_back(
        self,
        sent: Sequence[MissionItem],
        tol: Tolerance,
        *,
        acknowledged: bool = True,
        attempts: int = 3,
    ) -> list[MissionItem]:
        """The mission just uploaded, read back. A read-back that fails is said as such: "could
        not read it back" is a :class:`ReadBackError`, never "it differs". Each attempt resumes
        where the last one stopped (the items read stay read), so a link that drops out for a
        while costs the time it is out, not the whole read-back again."""
        got: dict[int, MissionItem] = {}
        expect: int | None = None
        self._last_count = None
        for attempt in range(attempts):
            try:
                # Late copies of our items reach an ArduPilot no longer receiving, which
                # answers each with MAV_MISSION_ERROR: left over from the upload, not a refusal.
                return self._download_into(
                    got, MAV_MISSION_TYPE_MISSION, expect, (*_LEFTOVER_ACKS, _AFTER_UPLOAD)
                )
            except LinkError as exc:
                expect = self._last_count
                if attempt < attempts - 1:
                    continue
                # What was read is compared all the same: a difference is a difference.
                wrong = self._partial_differences(sent, got, tol)
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
                    raise LinkError(
                        f"the mission read back differs from the upload ({read} before the "
                        f"link failed): {'; '.join(wrong[:5])}"
                    ) from None
                raise ReadBackError(
                    f"{said} but it could not be read back to verify it: {exc}. {read}"
                    f"{', all as uploaded' if got and expect is not None else ''}; the "
                    "read-back failed, so whether the vehicle holds this mission is unknown: "
                    "run `gcs-planner download` to check"
                ) from None
        raise AssertionError("unreachable")

    def _partial_differences(
        self, sent: Sequence[MissionItem], got: dict[int, MissionItem], tol: Tolerance
    ) -> list[str]:
        """The differences between the items read back so far and the ones sent."""
        out: list[str] = []
        for seq in sorted(got):
            if seq >= len(sent):
                out.append(f"item {seq}: read back, but only {len(sent)} items were uploaded")
            elif not (seq == 0 and keeps_home_item(self.firmware)):
                out.extend(f"item {seq}: {d}" for d in item_differences(sent[seq], got[seq], tol))
        return out

    def check_loiter_parameter(self) -> None:
        """Raise a :class:`LinkError` naming the parameter when the vehicle has no loiter-radius
        parameter under its firmware's name (autopilots stay silent about unknown names)."""
        firmware = self.firmware if self.firmware in FIRMWARES else "ardupilot"
        name = LOITER_RADIUS_PARAM[firmware][0]
        try:
            read_parameter(self.link, self._target(), name, timeout=self.timeout, retries=1)
        except LinkError:
            raise LinkError(
                f"the vehicle did not answer a read of {name}, the {firmware} loiter radius "
                "the plan's turning radius is set in; nothing was uploaded (use "
                "--keep-loiter-radius to upload without setting it)"
            ) from None

    # Missions by MAVFTP ------------------------------------------------------------------------
    def autopilot_capabilities(self) -> int:
        """AUTOPILOT_VERSION.capabilities: asked with MAV_CMD_REQUEST_MESSAGE, then the older
        MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES (both autopilots answer either); 0 when the
        vehicle says nothing (it offers no optional protocol then)."""
        if self.capabilities is not None:
            return self.capabilities
        ts, tc = self._target()
        asks = [
            self.mav.command_long_encode(ts, tc, mavlink.MAV_CMD_REQUEST_MESSAGE, 0,
                                         mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION,
                                         0, 0, 0, 0, 0, 0),
            self.mav.command_long_encode(ts, tc, mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
                                         0, 1, 0, 0, 0, 0, 0, 0),
        ]  # fmt: skip
        for attempt in range(min(self.retries, 2) + 1):
            self.link.send(asks[attempt % 2])
            deadline = time.monotonic() + self.timeout
            while (remaining := deadline - time.monotonic()) > 0:
                msg = self._recv(remaining, {"AUTOPILOT_VERSION"}, None)
                if msg is not None:
                    self.capabilities = int(msg.capabilities)
                    return self.capabilities
        self.capabilities = 0
        return 0

    def _use_ftp(self) -> bool:
        if self.transfer == "mission":
            return False
        if self.transfer == "ftp":
            return True
        # Only ArduPilot serves @MISSION (PX4 sets the FTP bit for its file system): any other
        # vehicle is not asked for its capabilities at all.
        if self.firmware != "ardupilot":
            return False
        return bool(self.autopilot_capabilities() & mavlink.MAV_PROTOCOL_CAPABILITY_FTP)

    def _ftp(self) -> FtpClient:
        return FtpClient(
            self.mav,
            self.link.send,
            lambda t: self._recv(t, {"FILE_TRANSFER_PROTOCOL"}, None),
            self._target(),
            timeout=self.timeout,
            retries=self.retries,
            extra_wait=self.radio.extra_wait,
            congested=self.radio.congested,
        )

    def _fallback(self, exc: FtpError) -> bool:
        """Whether an FTP failure sends an automatic choice back to the mission protocol: the
        vehicle has no mission file (or no FTP) at all; its file stayed busy through every
        reset and wait (the mission protocol does not share AP_Filesystem_Mission's one
        upload at a time); or one FTP request went unanswered through all its resends, which
        at 30 % loss each way befalls about one exchange in 60 (0.51 ** 6), where the mission
        protocol resends at the round trip's pace until nothing has come for its stall limit.
        Nothing an upload failing so sent was stored: the vehicle stores the file when it is
        closed, and a close whose answer was lost is not an FtpError (_Unconfirmed)."""
        if self.transfer != "auto":
            return False
        return exc.code in _NO_MISSION_FILE or isinstance(exc, (FtpBusy, FtpQuiet))

    def _ftp_upload(self, items: Sequence[MissionItem]) -> None:
        data = encode_mission(items)
        client = self._ftp()
        try:
            client.reset()
            reply = client.write(MISSION_PATH, data)
        finally:
            self.retry_count += client.retry_count
        if reply is None:
            raise _Unconfirmed(f"no answer came to the close of {MISSION_PATH}")
        if reply.opcode == NAK:
            raise UploadRefused(
                f"upload refused: the vehicle did not store {MISSION_PATH} when it was closed "
                f"(TerminateSession NAK: {reply.nak_text()}); ArduPilot refuses the whole file "
                "when its header's count and the items disagree or an item is one it does not "
                "store, and keeps the mission it had"
            )

    def _ftp_read(self, chunks: dict[int, bytes]) -> list[MissionItem]:
        client = self._ftp()
        try:
            data = client.read(MISSION_PATH, mission_length, chunks)
        finally:
            self.retry_count += client.retry_count
        # A command without a position carries in ArduPilot's file the x, y, z of the item read
        # before it (one item buffer per read call), which the vehicle does not store.
        return without_leftovers(decode_mission(data))

    def _ftp_read_back(
        self, sent: Sequence[MissionItem], tol: Tolerance, *, acknowledged: bool, attempts: int = 3
    ) -> list[MissionItem]:
        """The read-back by MAVFTP: as :meth:`_read_back`, resuming across attempts from the
        bytes already read."""
        chunks: dict[int, bytes] = {}
        for attempt in range(attempts):
            try:
                return self._ftp_read(chunks)
            except LinkError as exc:
                if attempt < attempts - 1:
                    continue
                said = (
                    "the vehicle acknowledged the close of the mission file"
                    if acknowledged
                    else "the vehicle never acknowledged the close of the mission file"
                )
                held = sum(len(c) for c in chunks.values())
                raise ReadBackError(
                    f"{said} but it could not be read back to verify it: {exc}. {held} bytes "
                    "were read back; the read-back failed, so whether the vehicle holds this "
                    "mission is unknown: run `gcs-planner download` to check"
                ) from None
        raise AssertionError("unreachable")

    def _ftp_crc_check(self, sent: Sequence[MissionItem]) -> str:
        """Empty when the vehicle's CRC of its mission file is that of the file it serves
        holding ``sent``; otherwise why not (the read-back then decides). Item 0 of that file is the
        vehicle's own home, so its first 48 bytes are read to predict the file; a home that
        moves between the two answers only costs the read-back."""
        if not sent:
            return "nothing was sent"
        client = self._ftp()
        try:
            head = client.read_head(MISSION_PATH, HEADER.size + ITEM.size)
            vehicle_crc = client.crc32(MISSION_PATH)
        except FtpError as exc:
            return f"no CRC: {exc}"
        finally:
            self.retry_count += client.retry_count
        if len(head) < HEADER.size + ITEM.size:
            return f"the file's first {len(head)} bytes hold no home item"
        magic, _, _, _, count = HEADER.unpack_from(head)
        if magic != MAGIC or count != len(sent):
            return f"the file's header says {count} items (magic 0x{magic:04x})"
        # ArduPilot serves its own home as item 0 (the read-back skips it likewise); any other
        # firmware is held to the item sent.
        home = (
            head[HEADER.size :] if keeps_home_item(self.firmware) else stored_item_bytes(sent[0], 0)
        )
        expected = crc32(stored_file(sent, home))
        if vehicle_crc != expected:
            return f"CRC 0x{vehicle_crc:08x}, expected 0x{expected:08x}"
        return ""

    # The whole job ----------------------------------------------------------------------------
    def upload_verified(
        self,
        items: Sequence[MissionItem],
        *,
        loiter_radius: float | None = None,
        tolerance: Tolerance | None = None,
    ) -> UploadReport:
        """Upload, read back and compare; optionally set the loiter radius (confirmed).

        A read-back that differs from the upload in any item, or in the number of items, is a
        :class:`LinkError` listing the differences: never a success.
        """
        start = time.perf_counter()
        self._target()
        retries_before = self.retry_count
        tol = tolerance or Tolerance()
        sent = [it.with_seq(i) if it.seq != i else it for i, it in enumerate(items)]
        unconfirmed: str | None = None
        self.transfer_used = "ftp" if self._use_ftp() else "mission"
        try:
            if self.transfer_used == "ftp":
                try:
                    self._ftp_upload(sent)
                except FtpError as exc:
                    if not self._fallback(exc):
                        raise
                    self.transfer_used = "mission"
            if self.transfer_used == "mission":
                self._upload(sent, MAV_MISSION_TYPE_MISSION)
        except _Unconfirmed as exc:
            # The read-back decides: the same mission is a success, anything else is not.
            unconfirmed = exc.reason
        uploaded = time.perf_counter()
        verify, crc_note = "read", ""
        if self.transfer_used == "ftp" and self.verify == "crc":
            crc_note = self._ftp_crc_check(sent)
            verify = "read" if crc_note else "crc"
        if verify == "crc":
            diffs = []  # the vehicle serves, byte for byte, the file of the items sent
        else:
            if self.transfer_used == "ftp":
                got = self._ftp_read_back(sent, tol, acknowledged=unconfirmed is None)
            else:
                got = self._read_back(sent, tol, acknowledged=unconfirmed is None)
            skip_home = keeps_home_item(self.firmware)
            diffs = mission_differences(list(items), got, skip_home=skip_home, tol=tol)
        if diffs:
            more = f"; and {len(diffs) - 5} more" if len(diffs) > 5 else ""
            shown = "; ".join(diffs[:5]) + more
            why = f" (every item was sent but {unconfirmed})" if unconfirmed else ""
            raise LinkError(f"the mission read back differs from the upload{why}: {shown}")
        verified = time.perf_counter()
        if loiter_radius is not None:
            set_loiter_radius(
                self.link,
                self._target(),
                loiter_radius,
                self.firmware if self.firmware in FIRMWARES else "ardupilot",
                timeout=self.timeout,
                retries=self.retries,
            )
        return UploadReport(
            items=len(items),
            seconds=time.perf_counter() - start,
            upload_seconds=uploaded - start,
            verify_seconds=verified - uploaded,
            retries=self.retry_count - retries_before,
            unacknowledged=unconfirmed is not None,
            transfer=self.transfer_used,
            verify=verify,
            crc_note=crc_note,
        )
