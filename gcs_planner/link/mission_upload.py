"""The mission protocol's upload, one work item per transfer: MISSION_COUNT, then each item the
vehicle requests, until its MISSION_ACK.

Answers MISSION_REQUEST and MISSION_REQUEST_INT alike, always with MISSION_ITEM_INT. An item
that gets no answer is sent again after the round-trip timeout, doubled for each resend in a
row, plus the slowdown the local radio's RADIO_STATUS calls for; no resend goes while that
radio says its buffer is nearly full (the first copy is still in it). A request for an item
sent less than a round-trip timeout ago crossed that copy and is not answered again. An
INVALID_SEQUENCE acknowledgement of a resent item says the vehicle already had it and its
request for the next one was lost: the next one is sent without waiting for the vehicle's own
re-request (ArduPilot's comes only after a second). Any other error result ends the transfer
with that result in words (:class:`~gcs_planner.errors.UploadRefused`).

A vehicle still inside an earlier upload of ours (one that died mid-transfer) is restarted:
requests it makes for that transfer before asking for item 0 of this one are not ours and are
ignored, and a MISSION_COUNT it refuses as busy is followed by a MISSION_ACK
OPERATION_CANCELLED and the count again, once (PX4 restarts only after a cancel; ArduPilot
restarts on the count of the same ids).

When every item was sent but the final acknowledgement never came, or came as an error to a
resent last item (ArduPilot, no longer receiving, answers any item with MAV_MISSION_ERROR),
the outcome is :attr:`~gcs_planner.link.outcome.TransferResult.UNCONFIRMED`: whether the
vehicle stored the mission is for a read-back to say.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Sequence
from typing import Any

from gcs_planner.errors import InputError, LinkError, UploadRefused
from gcs_planner.link.connection import mavlink
from gcs_planner.link.outcome import ACKNOWLEDGED, Outcome, unconfirmed
from gcs_planner.link.progress import Progress
from gcs_planner.link.protocol import describe_result, item_to_message
from gcs_planner.link.session import VehicleSession
from gcs_planner.link.validate import item_problem
from gcs_planner.mission.items import MissionItem

# Refusals of a MISSION_COUNT that mean "busy with another transfer": ArduPilot DENIED, PX4
# ERROR ("Mission upload busy"), and a cancel of the transfer it was in that crossed our count.
_BUSY = (
    mavlink.MAV_MISSION_DENIED,
    mavlink.MAV_MISSION_ERROR,
    mavlink.MAV_MISSION_OPERATION_CANCELLED,
)
_REQUESTS = {"MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK"}


def _span(first: int, last: int) -> str:
    return str(first) if first == last else f"{first}..{last}"


def numbered(items: Sequence[MissionItem]) -> list[MissionItem]:
    """``items`` with each one's seq its place in the mission."""
    return [it.with_seq(i) if it.seq != i else it for i, it in enumerate(items)]


def check_packable(mav: Any, items: Sequence[MissionItem], ts: int, tc: int) -> None:
    """Refuse, before the count goes out, an item MISSION_ITEM_INT cannot carry (a latitude
    in degE7 given as degrees overflows its int32): the caller's input, named by item."""
    for item in items:
        try:
            item_to_message(mav, item, ts, tc).pack(mav)
        except (struct.error, OverflowError, ValueError, TypeError):
            problem = item_problem(item)
            reason = f"{problem.field}: {problem.reason}" if problem else "does not pack"
            raise InputError(
                f"mission item {item.seq} cannot be sent in MISSION_ITEM_INT: {reason}"
            ) from None


class MissionUpload:
    """One upload of ``items`` to the session's vehicle; :meth:`run` sends it."""

    def __init__(
        self, session: VehicleSession, items: Sequence[MissionItem], mission_type: int
    ) -> None:
        self.session = session
        self.items = numbered(items)
        self.mission_type = mission_type
        self.count = len(self.items)
        self.target = (0, 0)
        self.count_msg: Any = None
        self.bar: Progress | None = None
        self.requested: int | None = None  # the item last sent, answering a request
        self.sent_at = 0.0
        self.resent = False
        self.attempts = 0  # resends in a row without progress, for the backoff
        self.copies: dict[int, float] = {}  # item -> when a copy of it last went out
        self.highest = -1  # the highest item the vehicle asked for
        self.sent_upto = -1  # the highest item sent, asked for or inferred
        self.last_progress = 0.0
        self.cancelled_once = False  # a busy refusal of the count has been answered with a cancel
        self.last_ack: int | None = None  # the last MISSION_ACK the vehicle sent that we went past
        self.early_ack_waits = -1  # timeouts since an ACCEPTED came before the last item was sent
        self.stale: int | None = None  # a request of an earlier transfer, ignored
        self.all_sent = self.count == 0  # every item has gone out at least once

    def run(self) -> Outcome:
        """Send the mission; its outcome, or a :class:`LinkError` (the vehicle is left idle:
        our transfer is cancelled)."""
        s = self.session
        ts, tc = self.target = s._target()
        check_packable(s.mav, self.items, ts, tc)
        self.count_msg = s.mav.mission_count_encode(ts, tc, self.count, self.mission_type)
        s.link.send(self.count_msg)
        self.bar = bar = s.progress("upload", self.count)
        self.sent_at = self.last_progress = time.monotonic()
        try:
            while True:
                outcome = self._step()
                if outcome is not None:
                    return outcome
        except LinkError:
            # Leave the vehicle idle rather than waiting out its upload timeout.
            s._cancel_transfer(self.mission_type)
            raise
        finally:
            bar.close()

    def _step(self) -> Outcome | None:
        """Wait for the vehicle's next answer and act on it; the outcome once there is one."""
        s = self.session
        if self.requested is None:
            wait = s.timeout * (2 ** min(self.attempts, 2)) + s.radio.extra_wait()
        else:
            wait = s._resend_wait(self.attempts)
        msg = s._recv(wait, _REQUESTS, self.mission_type)
        now = time.monotonic()
        if msg is None:
            return self._on_silence(now)
        if msg.get_type() == "MISSION_ACK":
            return self._on_ack(msg.type, now)
        self._on_request(int(msg.seq), now)
        return None

    def _send_item(self, seq: int, now: float) -> None:
        self.copies[seq] = now
        ts, tc = self.target
        self.session.link.send(item_to_message(self.session.mav, self.items[seq], ts, tc))

    def _send_next(self, seq: int, now: float) -> None:
        """Send ``seq`` as the answer to the vehicle's latest request (asked or inferred)."""
        self.requested = seq
        self.sent_upto = max(self.sent_upto, seq)
        self.all_sent = self.all_sent or self.sent_upto == self.count - 1
        self.resent, self.sent_at = False, now
        self._send_item(seq, now)

    def _on_silence(self, now: float) -> Outcome | None:
        """No answer within the wait: send the last thing again, or give up."""
        s = self.session
        if self.early_ack_waits >= 0:
            self.early_ack_waits += 1
        if self.early_ack_waits > 2 or now - self.last_progress > s._stall_limit():
            if self.all_sent and self.early_ack_waits < 0:
                return unconfirmed("no MISSION_ACK came for the last item")
            raise self._stalled()
        if s.radio.congested():
            return None  # the radio's buffer still holds the first copy: no second
        s.retry_count += 1
        self.attempts += 1
        self.resent, self.sent_at = True, now
        if self.requested is None:
            s.link.send(self.count_msg)
        else:
            self._send_item(self.requested, now)
        return None

    def _on_ack(self, result: int, now: float) -> Outcome | None:
        """A MISSION_ACK: the end of the upload, a leftover, a hint, or a refusal."""
        if result == mavlink.MAV_MISSION_ACCEPTED:
            if self.count == 0 or self.sent_upto == self.count - 1:
                return ACKNOWLEDGED
            if self.highest >= 0:
                # Our transfer is under way and the vehicle says it is over: either a late
                # copy of an earlier transfer's answer (a request follows) or the vehicle
                # ended ours early (nothing follows).
                self.last_ack = result
                self.early_ack_waits = max(self.early_ack_waits, 0)
            return None  # before our first request: an earlier transfer's answer
        if result == mavlink.MAV_MISSION_INVALID_SEQUENCE:
            self.last_ack = result
            self._on_invalid_sequence(now)
            return None
        if (
            self.all_sent
            and result == mavlink.MAV_MISSION_ERROR
            and self.requested == self.count - 1
            and self.resent
        ):
            # ArduPilot's answer to an item when it is not receiving: the first copy of the
            # last item ended the transfer and its ACK was lost, or the transfer failed; only
            # the read-back can tell which.
            return unconfirmed(
                f"the vehicle answered the resent last item with MISSION_ACK "
                f"{describe_result(result)}"
            )
        if self.requested is None and not self.cancelled_once and result in _BUSY:
            # Refused before it asked for anything: most often it is still inside an earlier
            # upload of ours that died. Cancel that one and count again.
            self.cancelled_once = True
            self.session._cancel_transfer(self.mission_type)
            self.session.link.send(self.count_msg)
            self.sent_at = self.last_progress = now
            return None
        where = "MISSION_COUNT" if self.requested is None else f"item {self.sent_upto}"
        raise UploadRefused(f"upload refused after {where}: MISSION_ACK {describe_result(result)}")

    def _on_invalid_sequence(self, now: float) -> None:
        """In reply to a resent item j: the vehicle has j (it would have taken it otherwise)
        and its request for j + 1 was lost. A wrong guess costs only a refusal; the vehicle's
        own re-request sets us right."""
        if not (self.resent and self.requested is not None and self.requested + 1 < self.count):
            return
        nxt = self.requested + 1
        if now - self.copies.get(nxt, -1e9) < self.session._resend_wait(0):
            return  # a copy of it is already on its way
        self.attempts = 0  # progress: the vehicle has the item resent
        self._send_next(nxt, now)

    def _on_request(self, seq: int, now: float) -> None:
        """The vehicle asks for item ``seq``: send it, unless a copy is still on its way."""
        if not 0 <= seq < self.count:
            if self.highest < 0:
                self.stale = seq
                return  # a request of an earlier, longer transfer
            raise LinkError(f"the vehicle requested item {seq} of a {self.count}-item mission")
        if seq > self.sent_upto + 1:
            if self.highest < 0:
                # It has not asked for item 0 of this transfer yet: a re-request left over
                # from an earlier one, which our count is about to restart.
                self.stale = seq
                return
            raise LinkError(
                f"the vehicle requested item {seq} after item {self.sent_upto}: it skipped "
                f"item{'s' if seq - self.sent_upto > 2 else ''} "
                f"{_span(self.sent_upto + 1, seq - 1)}, which it was never sent (a vehicle "
                "asks for every item in turn); the upload was cancelled"
            )
        s = self.session
        if self.requested is not None and seq == self.requested + 1 and not self.resent:
            s._rtt.sample(now - self.sent_at)
        if seq > self.highest:
            self.last_progress = now
            self.early_ack_waits = -1
            self.attempts = 0
        if seq <= self.highest and now - self.copies.get(seq, -1e9) < s._resend_wait(0):
            # A re-request that crossed the copy we sent: that copy can still arrive, and a
            # second one would only queue behind it on a slow link.
            return
        self.highest = max(self.highest, seq)
        self._send_next(seq, now)
        assert self.bar is not None  # made when the count went out
        self.bar.update(self.highest + 1)

    def _stalled(self) -> LinkError:
        """Why the upload made no progress for its stall limit, in the vehicle's last words."""
        if self.last_ack == mavlink.MAV_MISSION_ACCEPTED:
            return LinkError(
                f"the vehicle ended the upload early, after item {self.sent_upto} of items 0.."
                f"{self.count - 1}, with MISSION_ACK {describe_result(self.last_ack)}, and asked "
                "for no more: what it holds is unknown (run `gcs-planner download` to see)"
            )
        where = "MISSION_COUNT" if self.requested is None else f"item {self.requested}"
        error = self.session._give_up(f"upload stalled after {where}")
        extra = ""
        if self.last_ack is not None:
            extra = f"; the vehicle's last answer was MISSION_ACK {describe_result(self.last_ack)}"
        elif self.requested is None and self.stale is not None:
            extra = (
                f"; the vehicle asked only for item {self.stale}, never for item 0: it did not "
                "restart its earlier transfer"
            )
        return LinkError(f"{error}{extra}")
