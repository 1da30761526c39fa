"""The mission protocol's download, one work item per transfer: MISSION_REQUEST_LIST, the
vehicle's MISSION_COUNT, a MISSION_REQUEST_INT for each item, then our MISSION_ACK; and the
download by MAVFTP, checked end to end.

How the requests go follows the autopilot (:meth:`VehicleSession.requests_in_sequence`, the
record's ``protocol.requests_in_sequence``). PX4 answers only a request for the next item or the
last one again and ends the transfer with MISSION_ACK MAV_MISSION_ERROR on any other
(``MavlinkMissionManager::handle_mission_request_both``, src/modules/mavlink/
mavlink_mission.cpp): one request is kept out, the next asked when its answer is in, so a loss
can only make a request be asked again, which PX4 answers. ArduPilot answers every request on
its own (``MissionItemProtocol::handle_mission_request_int``, libraries/GCS_MAVLink/
MissionItemProtocol.cpp): several are kept out, as MAVProxy does, as many as the link carries
(:class:`~gcs_planner.link.pacing.Window`: delivery rate times the round trip, from the
session's ``window``); none is added while the local radio says its buffer is nearly full. A
request is asked again when later items overtook its answer (the link is in order, so it was
lost) or after the round-trip timeout, doubled for each time it was asked already: never while
its first copy can still be in the channel.

A MISSION_ACK with an error after the count is never let pass: the vehicle ended the transfer
(PX4 goes idle and ignores later requests), so it is asked again from MISSION_REQUEST_LIST, up to
the session's retries, and then it is a :class:`LinkError` naming the vehicle's answer. One that
says MISSION_REQUEST_INT is unsupported turns the requests to the older MISSION_REQUEST.

A mission read by MAVFTP is checked against the vehicle's own CRC-32 of its file
(:func:`~gcs_planner.link.mission_by_ftp.read_file_checked`); where the vehicle offers no CRC it
is read again by the mission protocol and the two compared. A file that fails either check is a
:class:`LinkError`: nothing is taken from it.
"""

from __future__ import annotations

import itertools
import time
from typing import Any

from gcs_planner.errors import LinkError
from gcs_planner.link.connection import mavlink
from gcs_planner.link.ftp import FtpError
from gcs_planner.link.mission_by_ftp import falls_back, read_file_checked, use_ftp
from gcs_planner.link.pacing import Window
from gcs_planner.link.protocol import describe_result, item_from_message, mission_differences
from gcs_planner.link.session import VehicleSession
from gcs_planner.link.validate import item_problem
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

# The most requests outstanding at once (32 items of 49 bytes fit SiK's serial buffer).
MAX_WINDOW = 32
# An answer that arrives after later ones overtook it is taken as lost after this many later
# answers (the links are in order; a radio or router reorders little): asked again at once.
REORDER_SLACK = 3
LEFTOVER_ACKS = (mavlink.MAV_MISSION_ACCEPTED, mavlink.MAV_MISSION_INVALID_SEQUENCE)
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
            mission, unchecked = read_file_checked(session)
        except FtpError as exc:
            if not falls_back(session, exc):
                raise
            session.transfer_used = "mission"
        else:
            if unchecked:
                _confirm_by_mission_protocol(session, mission, unchecked)
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


def _confirm_by_mission_protocol(
    session: VehicleSession, by_file: list[MissionItem], why: str
) -> None:
    """The mission read by MAVFTP, which the vehicle's CRC could not vouch for (``why``),
    read again by the mission protocol: the two must be the same mission."""
    by_protocol = MissionDownload(session, {}, MAV_MISSION_TYPE_MISSION).run()
    diffs = mission_differences(by_protocol, by_file)
    if diffs:
        more = f"; and {len(diffs) - 5} more" if len(diffs) > 5 else ""
        raise LinkError(
            f"the mission read by MAVFTP ({why}) is not the one the mission protocol reads: "
            f"{'; '.join(diffs[:5])}{more}. It was altered on the way, or changed meanwhile: "
            "download it again"
        )


def download_count(
    session: VehicleSession, mission_type: int, leftovers: tuple[int, ...] = LEFTOVER_ACKS
) -> int:
    """The vehicle's MISSION_COUNT, asked with MISSION_REQUEST_LIST until it answers (a vehicle
    busy receiving answers DENIED until it times out or is cancelled). ``leftovers``: the
    MISSION_ACK results taken as answers to an earlier transfer."""
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
            if msg.type in leftovers:
                continue  # leftovers of an earlier transfer
            raise LinkError(f"download refused: {describe_result(msg.type)}")
        # A request we did not start: a late duplicate of an old MISSION_COUNT put the
        # vehicle in receive mode.
        session._cancel_transfer(mission_type)


class TransferEnded(Exception):
    """The vehicle ended the download with a MISSION_ACK error (``result``)."""

    def __init__(self, result: int) -> None:
        super().__init__(result)
        self.result = result


class MissionDownload:
    """One download into ``got`` (items already there are not asked for again where the
    autopilot answers requests in any order, so a read-back retried after a failure resumes).
    ``expect``: the count an earlier attempt read; a different one now means the mission
    changed and ``got`` is started afresh. ``leftovers``: the MISSION_ACK results taken, before
    the count comes, as answers to an earlier transfer (the read-back's include the errors an
    ArduPilot no longer receiving sends to our last items: on an in-order link they all come
    before the count)."""

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
        self.in_sequence = session.requests_in_sequence()
        self.request_int = True  # MISSION_REQUEST_INT until the vehicle says it has none
        # The classic client (a window of 1), or an autopilot that serves in sequence: one
        # request at a time, always.
        fixed = session.window == 1 or self.in_sequence
        start = 1 if self.in_sequence else session.window
        self.window = Window(start, low=1 if fixed else 2, high=1 if fixed else MAX_WINDOW)
        self.tickets = itertools.count()
        self._fresh_transfer()

    def _fresh_transfer(self) -> None:
        """The state of one transfer, from its MISSION_REQUEST_LIST on."""
        self.sent: dict[int, tuple[float, int]] = {}  # seq -> (when last asked, times asked)
        self.ticket: dict[int, int] = {}  # seq -> the number of its last request, in order
        self.overtaken: dict[int, int] = {}  # seq -> answers to later requests that came first
        self.taken: set[int] = set()  # items answered in this transfer
        self.missing: list[int] = []
        self.next_new = 0  # index into missing
        self.stalls = 0  # timeouts in a row with no answer: the backoff of the whole link
        self.behind: dict[int, bool] = {}  # seq -> resent while an earlier one was unanswered
        # The timer resends only once a receive has found nothing waiting: a process kept off
        # the CPU past the timer finds the answer it waited for already here, not lost.
        self.drained = False
        self.last_progress = time.monotonic()

    def run(self) -> list[MissionItem]:
        """The vehicle's mission, in seq order; asked again from the start each time the
        vehicle ends the transfer, up to the session's retries."""
        s = self.session
        ts, tc = self.target = s._target()
        ended = 0
        while True:
            try:
                self._transfer()
                break
            except TransferEnded as exc:
                ended += 1
                if ended > s.retries:
                    raise LinkError(
                        f"download refused: the vehicle ended it {ended} times, last with "
                        f"MISSION_ACK {describe_result(exc.result)}"
                    ) from None
                s.retry_count += 1
                self._fresh_transfer()
        done = s.mav.mission_ack_encode(ts, tc, mavlink.MAV_MISSION_ACCEPTED, self.mission_type)
        s.link.send(done)
        return [self.got[seq] for seq in range(self.count)]

    def _transfer(self) -> None:
        """One transfer from MISSION_REQUEST_LIST until every item is in."""
        s = self.session
        count = self.count = download_count(s, self.mission_type, self.leftovers)
        if self.expect is not None and count != self.expect:
            self.got.clear()
        self.expect = count
        s._last_count = count
        for seq in [seq for seq in self.got if seq >= count]:
            del self.got[seq]
        if not self.in_sequence:
            self.taken = set(self.got)  # asked in any order: what is held is not asked again
        self.missing = [seq for seq in range(count) if seq not in self.taken]
        bar = s.progress("download", count)
        bar.update(len(self.taken))
        self.last_progress = time.monotonic()
        try:
            while len(self.taken) < count:
                now = time.monotonic()
                congested = s.radio.congested()
                self._resend(now, congested)
                self._fill(now, congested)
                msg = s._recv(max(self._wait(now), 0.005), _ANSWERS, self.mission_type)
                now = time.monotonic()
                self.drained = msg is None
                if self._take(msg, now):
                    bar.update(len(self.taken))
        finally:
            bar.close()
            s.window_used = self.window.size

    def _request(self, seq: int) -> None:
        ts, tc = self.target
        mav = self.session.mav
        encode = mav.mission_request_int_encode if self.request_int else mav.mission_request_encode
        self.session.link.send(encode(ts, tc, seq, self.mission_type))

    def _oldest(self) -> int | None:
        return min(self.sent, key=self.ticket.__getitem__, default=None)

    def _ask_again(self, seq: int, now: float) -> None:
        """Request ``seq`` again (a resend: its round trip is not sampled, Karn's rule)."""
        self.session.retry_count += 1
        self.behind[seq] = any(self.ticket[o] < self.ticket[seq] for o in self.sent if o != seq)
        self.sent[seq] = (now, self.sent[seq][1] + 1)
        self.ticket[seq], self.overtaken[seq] = next(self.tickets), 0
        self._request(seq)

    def _resend(self, now: float, congested: bool) -> None:
        """Ask again for what is lost: overtaken by later answers, or the oldest request past
        its timer. Only the oldest request is timed (TCP's one retransmission timer): on an
        in-order link every later answer waits behind its answer, so timing them too would ask
        again for what is still on its way."""
        s = self.session
        oldest = self._oldest()
        for seq, (when, _) in list(self.sent.items()):
            lost = self.overtaken[seq] >= REORDER_SLACK
            due = seq == oldest and self.drained and now - when > s._resend_wait(self.stalls)
            if not (lost or due) or congested:
                continue
            self.window.lost()
            self._ask_again(seq, now)
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
            if seq in self.taken:
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

    def _on_ack(self, result: int, now: float) -> None:
        """A MISSION_ACK in the middle of the transfer: a leftover, the old spelling asked
        for, or the vehicle ending the transfer (:class:`TransferEnded`)."""
        if result in LEFTOVER_ACKS:
            return  # leftovers of an earlier transfer
        if result == mavlink.MAV_MISSION_UNSUPPORTED and self.request_int:
            # No MISSION_REQUEST_INT here: the deprecated MISSION_REQUEST, which every
            # autopilot answers (with MISSION_ITEM), for what is out.
            self.request_int = False
            for seq in list(self.sent):
                self._ask_again(seq, now)
            return
        raise TransferEnded(result)

    def _take(self, msg: Any | None, now: float) -> bool:
        """Act on what came (None: nothing); True when it was a new item of the mission."""
        s = self.session
        if msg is None:
            if now - self.last_progress > s._stall_limit():
                first = min(set(range(self.count)) - self.taken)
                raise s._give_up(f"download: item {first}")
            return False
        if msg.get_type() == "MISSION_ACK":
            self._on_ack(int(msg.type), now)
            return False
        seq = int(msg.seq)
        if seq in self.taken:
            # The answer to a request asked again (the first answer was late, not lost), or
            # the resend's after it.
            s.late_answers += 1
            s.hasty_resends += self.behind.get(seq, False)
            return False
        if not 0 <= seq < self.count or (self.in_sequence and seq not in self.sent):
            # Not an item of this mission; or, served in sequence, the late answer to an
            # earlier transfer's request: the vehicle is to be asked for it in its turn.
            return False
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
        self.taken.add(seq)
        self.last_progress = now
        return True
