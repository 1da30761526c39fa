"""The mission protocol's download, one work item per transfer: MISSION_REQUEST_LIST, the
vehicle's MISSION_COUNT, a MISSION_REQUEST_INT for each item with several requests outstanding
(as MAVProxy does), then our MISSION_ACK; and the read-back after an upload, which resumes
where a failed attempt stopped.

How many requests are out at once follows the link (:class:`~gcs_planner.link.pacing.Window`:
delivery rate times the round trip), starting from the session's ``window``; none is added
while the local radio says its buffer is nearly full. A request is asked again when later items
overtook its answer (the link is in order, so it was lost) or after the round-trip timeout,
doubled for each time it was asked already: never while its first copy can still be in the
channel.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from typing import Any

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.errors import LinkError
from gcs_planner.link.connection import mavlink
from gcs_planner.link.ftp import FtpError
from gcs_planner.link.mission_by_ftp import falls_back, read_file, use_ftp
from gcs_planner.link.outcome import ReadBackError
from gcs_planner.link.pacing import Window
from gcs_planner.link.protocol import (
    Tolerance,
    describe_result,
    item_differences,
    item_from_message,
)
from gcs_planner.link.session import VehicleSession
from gcs_planner.link.validate import item_problem
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

# The most requests outstanding at once (32 items of 49 bytes fit SiK's serial buffer).
MAX_WINDOW = 32
# An answer that arrives after later ones overtook it is taken as lost after this many later
# answers (the links are in order; a radio or router reorders little): asked again at once.
REORDER_SLACK = 3
LEFTOVER_ACKS = (mavlink.MAV_MISSION_ACCEPTED, mavlink.MAV_MISSION_INVALID_SEQUENCE)
# Late copies of our items reach an ArduPilot no longer receiving, which answers each with
# MAV_MISSION_ERROR: left over from the upload, not a refusal.
_AFTER_UPLOAD = mavlink.MAV_MISSION_ERROR
_ANSWERS = {"MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_ACK"}


def download(session: VehicleSession, mission_type: int, *, validate: bool) -> list[MissionItem]:
    """The vehicle's mission: its file by MAVFTP when the session uses it (back to the mission
    protocol on the failures an automatic choice falls back on), else by the mission
    protocol; the way it went is left in ``session.transfer_used``.

    With ``validate`` an item no mission file may hold (validate.py: unknown frame or command,
    a position out of range or not set, a non-finite altitude or parameter) is a
    :class:`LinkError` naming its seq and field: what a vehicle sends is input like any other.
    The read-back after an upload compares instead."""
    mission: list[MissionItem] | None = None
    session.transfer_used = "mission"
    if mission_type == MAV_MISSION_TYPE_MISSION and use_ftp(session):
        session.transfer_used = "ftp"
        try:
            mission = read_file(session, {})
        except FtpError as exc:
            if not falls_back(session, exc):
                raise
            session.transfer_used = "mission"
    if mission is None:
        mission = MissionDownload(session, {}, mission_type).run()
    if validate:
        for item in mission:
            problem = item_problem(item)
            if problem is not None:
                raise LinkError(
                    f"the vehicle sent an invalid mission item: seq {item.seq}, field "
                    f"{problem.field!r}: {problem.reason}"
                )
    return mission


def download_count(session: VehicleSession, mission_type: int) -> int:
    """The vehicle's MISSION_COUNT, asked with MISSION_REQUEST_LIST until it answers (a vehicle
    busy receiving answers DENIED until it times out or is cancelled)."""
    ts, tc = session._target()
    request_list = session.mav.mission_request_list_encode(ts, tc, mission_type)
    session.link.send(request_list)
    attempts = 0
    while True:
        msg = session._recv(
            session.timeout,
            {"MISSION_COUNT", "MISSION_ACK", "MISSION_REQUEST", "MISSION_REQUEST_INT"},
            mission_type,
        )
        if msg is None or (
            msg.get_type() == "MISSION_ACK" and msg.type == mavlink.MAV_MISSION_DENIED
        ):
            # DENIED: the vehicle is busy receiving; it will time out or be cancelled.
            attempts += 1
            if attempts > session.retries:
                if msg is not None:
                    raise LinkError(f"download refused: {describe_result(msg.type)}")
                raise session._give_up("download: MISSION_REQUEST_LIST")
            session.retry_count += 1
            if msg is not None:
                time.sleep(min(session.timeout, 0.2))
            session.link.send(request_list)
            continue
        kind = msg.get_type()
        if kind == "MISSION_COUNT":
            return int(msg.count)
        if kind == "MISSION_ACK":
            if msg.type in LEFTOVER_ACKS:
                continue  # leftovers of an earlier transfer
            raise LinkError(f"download refused: {describe_result(msg.type)}")
        # A request we did not start: a late duplicate of an old MISSION_COUNT put the
        # vehicle in receive mode.
        session._cancel_transfer(mission_type)


class MissionDownload:
    """One download into ``got`` (items already there are not asked for again, so a read-back
    retried after a failure resumes). ``expect``: the count an earlier attempt read; a
    different one now means the mission changed and ``got`` is started afresh. ``leftovers``:
    the MISSION_ACK results taken as answers to an earlier transfer."""

    def __init__(
        self,
        session: VehicleSession,
        got: dict[int, MissionItem],
        mission_type: int,
        expect: int | None = None,
        leftovers: tuple[int, ...] = LEFTOVER_ACKS,
    ) -> None:
        self.session = session
        self.got = got
        self.mission_type = mission_type
        self.expect = expect
        self.leftovers = leftovers
        self.target = (0, 0)
        self.count = 0
        self.sent: dict[int, tuple[float, int]] = {}  # seq -> (when last asked, times asked)
        self.ticket: dict[int, int] = {}  # seq -> the number of its last request, in order
        self.overtaken: dict[int, int] = {}  # seq -> answers to later requests that came first
        self.tickets = itertools.count()
        fixed = session.window == 1  # the classic client: one request at a time, always
        self.window = Window(session.window, low=1 if fixed else 2, high=1 if fixed else MAX_WINDOW)
        self.missing: list[int] = []
        self.next_new = 0  # index into missing
        self.stalls = 0  # timeouts in a row with no answer: the backoff of the whole link
        self.behind: dict[int, bool] = {}  # seq -> resent while an earlier one was unanswered
        # The timer resends only once a receive has found nothing waiting: a process kept off
        # the CPU past the timer finds the answer it waited for already here, not lost.
        self.drained = False
        self.last_progress = 0.0

    def run(self) -> list[MissionItem]:
        """The vehicle's mission, in seq order."""
        s = self.session
        ts, tc = self.target = s._target()
        count = self.count = download_count(s, self.mission_type)
        if self.expect is not None and count != self.expect:
            self.got.clear()
        s._last_count = count
        bar = s.progress("download", count)
        bar.update(len(self.got))
        self.last_progress = time.monotonic()
        self.missing = [seq for seq in range(count) if seq not in self.got]
        try:
            while len(self.got) < count:
                now = time.monotonic()
                congested = s.radio.congested()
                self._resend(now, congested)
                self._fill(now, congested)
                msg = s._recv(max(self._wait(now), 0.005), _ANSWERS, self.mission_type)
                now = time.monotonic()
                self.drained = msg is None
                if self._take(msg, now):
                    bar.update(len(self.got))
        finally:
            bar.close()
            s.window_used = self.window.size
        done = s.mav.mission_ack_encode(ts, tc, mavlink.MAV_MISSION_ACCEPTED, self.mission_type)
        s.link.send(done)
        return [self.got[seq] for seq in range(count)]

    def _request(self, seq: int) -> None:
        ts, tc = self.target
        self.session.link.send(
            self.session.mav.mission_request_int_encode(ts, tc, seq, self.mission_type)
        )

    def _oldest(self) -> int | None:
        return min(self.sent, key=self.ticket.__getitem__, default=None)

    def _resend(self, now: float, congested: bool) -> None:
        """Ask again for what is lost: overtaken by later answers, or the oldest request past
        its timer. Only the oldest request is timed (TCP's one retransmission timer): on an
        in-order link every later answer waits behind its answer, so timing them too would ask
        again for what is still on its way."""
        s = self.session
        oldest = self._oldest()
        for seq, (when, asked) in list(self.sent.items()):
            lost = self.overtaken[seq] >= REORDER_SLACK
            due = seq == oldest and self.drained and now - when > s._resend_wait(self.stalls)
            if not (lost or due) or congested:
                continue
            s.retry_count += 1
            self.behind[seq] = any(self.ticket[o] < self.ticket[seq] for o in self.sent if o != seq)
            self.window.lost()
            self.sent[seq] = (now, asked + 1)
            self.ticket[seq], self.overtaken[seq] = next(self.tickets), 0
            self._request(seq)
            if due:
                self.stalls += 1
                # The timer restarts for what is still out, as TCP's does.
                for other, (_, n) in self.sent.items():
                    if other != seq:
                        self.sent[other] = (now, n)

    def _fill(self, now: float, congested: bool) -> None:
        """Ask for new items while the window has room and the radio is not full."""
        while (
            len(self.sent) < self.window.size
            and self.next_new < len(self.missing)
            and not congested
        ):
            seq = self.missing[self.next_new]
            self.next_new += 1
            if seq in self.got:
                continue
            self.sent[seq] = (now, 1)
            self.ticket[seq], self.overtaken[seq] = next(self.tickets), 0
            self._request(seq)

    def _wait(self, now: float) -> float:
        """Until the oldest request's timer runs out."""
        oldest = self._oldest()
        if oldest is None:
            return self.session._resend_wait(0)
        return self.session._resend_wait(self.stalls) - (now - self.sent[oldest][0])

    def _take(self, msg: Any | None, now: float) -> bool:
        """Act on what came (None: nothing); True when it was a new item of the mission."""
        s = self.session
        if msg is None:
            if now - self.last_progress > s._stall_limit():
                first = min(set(range(self.count)) - set(self.got))
                raise s._give_up(f"download: item {first}")
            return False
        if msg.get_type() == "MISSION_ACK":
            if msg.type in self.leftovers:
                return False  # leftovers of an earlier transfer
            raise LinkError(f"download refused: {describe_result(msg.type)}")
        seq = int(msg.seq)
        if seq in self.got:
            # The answer to a request asked again (the first answer was late, not lost), or
            # the resend's after it.
            s.late_answers += 1
            s.hasty_resends += self.behind.get(seq, False)
            return False
        if not 0 <= seq < self.count:
            return False  # not an item of this mission
        limited = len(self.sent) >= self.window.size
        asked = self.sent.pop(seq, None)
        mine = self.ticket.pop(seq, None)
        self.overtaken.pop(seq, None)
        if mine is not None:
            for other, theirs in self.ticket.items():
                if theirs < mine:
                    self.overtaken[other] += 1
        if asked is not None and asked[1] == 1:
            # Karn's rule: a round trip only from a request asked once.
            s._rtt.sample(now - asked[0])
            self.window.rtt(now - asked[0])
        self.window.delivered(now, limited)
        self.stalls = 0
        self.got[seq] = item_from_message(msg)
        self.last_progress = now
        return True


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
    where the last one stopped (the items read stay read), so a link that drops out for a
    while costs the time it is out, not the whole read-back again."""
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
