"""MAVLink FTP, ground-station side: the reads and writes of one file with burst reads and
resumption of what a lossy link lost.

The payload and its codes are :mod:`gcs_planner.link.ftp_payload`'s (re-exported here).

What the vehicle sends is input like any other: a size over 239, data past the end of the
file, a reply to a session that is not ours, or two different contents for one offset end the
transfer with a :class:`FtpError` that says which, never a traceback.

Why not pymavlink's ``mavftp.MAVFTP`` (read in pymavlink 2.4.50): it reads the connection
itself (``master.recv_match`` for FILE_TRANSFER_PROTOCOL only), so it cannot share the session's
receive loop, which keeps our heartbeat going, takes only the pinned vehicle's messages and
reads the radio's RADIO_STATUS for the pacing. Its timers are fixed (``retry_time`` 0.5 s,
``read_retry_time`` 1 s, ``idle_detection_time`` 3.7 s, a 5 s stall) where these follow the
measured round trip and the radio's slowdown, and it does not hold back while the radio says its
buffer is full. It keeps no bytes across sessions, where ArduPilot closes a session whose
replies could not go for 3 s and a read here goes on in a new one from what it has. It does not
take a file's length from its header (ArduPilot's stat of mission.dat says 1 MiB). A refused
open is not asked again after ResetSessions (AP_Filesystem_Mission takes one upload at a time,
and a lost open ACK leaves the file held by the first copy). It hands back no CRC value
(``cmd_crc`` logs it), so a download cannot be checked end to end against the vehicle's CRC,
and its windows (``max_backlog`` 5 gap reads, ``write_qsize`` 5 writes) stay the same
whatever the resends say, where these back off on a link whose radio does not report its
buffer. What a hostile vehicle sends is logged and returned as codes, not ended with an error
that names it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from gcs_planner.link.ftp_payload import (
    ACK,
    BURST_READ_FILE,
    CALC_FILE_CRC32,
    CREATE_FILE,
    DATA_MAX,
    EOF,
    ERRORS,
    FAIL_ERRNO,
    FILE_NOT_FOUND,
    LIST_DIRECTORY,
    NAK,
    NONE,
    OPEN_FILE_RO,
    OPEN_FILE_WO,
    PAYLOAD_LEN,
    READ_FILE,
    REMOVE_FILE,
    RESET_SESSIONS,
    TERMINATE_SESSION,
    UNKNOWN_COMMAND,
    WRITE_FILE,
    FtpBusy,
    FtpError,
    FtpQuiet,
    Packet,
    pack,
    unpack,
)
from gcs_planner.link.ftp_pieces import contiguous, gaps, take
from gcs_planner.link.pacing import Backoff, Window
from gcs_planner.link.rtt import RoundTrip

__all__ = [
    "NONE",
    "TERMINATE_SESSION",
    "RESET_SESSIONS",
    "LIST_DIRECTORY",
    "OPEN_FILE_RO",
    "READ_FILE",
    "CREATE_FILE",
    "WRITE_FILE",
    "REMOVE_FILE",
    "OPEN_FILE_WO",
    "CALC_FILE_CRC32",
    "BURST_READ_FILE",
    "ACK",
    "NAK",
    "ERRORS",
    "FAIL_ERRNO",
    "EOF",
    "UNKNOWN_COMMAND",
    "FILE_NOT_FOUND",
    "DATA_MAX",
    "PAYLOAD_LEN",
    "FtpError",
    "FtpQuiet",
    "FtpBusy",
    "Packet",
    "pack",
    "unpack",
    "FtpClient",
]

WRITE_WINDOW = 6  # WriteFile requests out at once, at most
FIRST_WAIT_S = 0.5
SESSION_REOPENS = 2
SESSION_LOST = (1, 4, 10)  # Fail, InvalidSession, FileNotFound: the session is gone
# Refusals of an open that say the file or the sessions are in use, by an earlier copy of the
# same open or by someone else, not that the file cannot be had: Fail (a file already open in
# the session), FailErrno (AP_Filesystem_Mission::open allows one upload at a time and leaves
# errno as it was, so GCS_FTP::error sends FailErrno with that errno, or FileExists where it
# happens to be EEXIST), NoSessionsAvailable (every session answered in the last 3 s:
# GCS_FTP::worker).
OPEN_BUSY = (1, 2, 5, 8)


Recv = Callable[[float], Any]


class FtpClient:
    """One file at a time with a vehicle over ``send``/``recv`` (the mission client's, so that
    heartbeats and the radio's RADIO_STATUS are kept up during a transfer).

    ``recv(timeout)`` returns the next FILE_TRANSFER_PROTOCOL message from the vehicle or None.
    ``congested()`` says the local radio's buffer is nearly full (no new request then).
    """

    def __init__(
        self,
        mav: Any,
        send: Callable[[Any], None],
        recv: Recv,
        target: tuple[int, int],
        *,
        timeout: float = 1.5,
        retries: int = 5,
        extra_wait: Callable[[], float] = lambda: 0.0,
        congested: Callable[[], bool] = lambda: False,
        radio_reports: Callable[[], bool] = lambda: False,
        hint: Callable[[], str] = lambda: "",
    ) -> None:
        self.mav = mav
        self._send = send
        self._recv = recv
        self.target = target
        self.timeout = timeout
        self.retries = retries
        self.extra_wait = extra_wait
        self.congested = congested
        self.radio_reports = radio_reports  # a radio reports its buffer (RADIO_STATUS)
        self.hint = hint  # what to add to a silence (the session's: signing may be why)
        # Resends wait the measured round trip of FTP requests (RFC 6298, Karn's rule), from
        # FIRST_WAIT_S until there is a sample: a 260-byte WriteFile on a TDM radio takes a
        # round and a serial time, longer than the mission protocol's item timeout.
        self._rtt = RoundTrip(floor=0.03, ceiling=timeout)
        self.seq = 0
        self.session = 0
        self.retry_count = 0
        self.foreign_sessions: set[int] = set()  # sessions answered that are not ours
        self.last_resent = False  # the last exchange needed a resend

    def resend_wait(self, attempts: int) -> float:
        """The round-trip timeout (FIRST_WAIT_S before a sample), doubled per resend in a row
        up to the protocol timeout, plus the local radio's slowdown. While a radio reports its
        buffer, the doubling starts past the fourth resend (a full buffer is reported, so a few
        losses in a row are the channel's); without reports from the first (RFC 6298, 5.5): the
        answer may be waiting in the link's queue, which a copy would only lengthen."""
        base = self._rtt.timeout if self._rtt.srtt is not None else FIRST_WAIT_S
        doublings = min(max(0, attempts - (4 if self.radio_reports() else 0)), 8)
        return max(base, min(base * 2**doublings, self.timeout)) + self.extra_wait()

    # One request and its reply ----------------------------------------------------------------
    def _request(self, opcode: int, offset: int = 0, data: bytes = b"", size: int | None = None,
                 seq: int | None = None) -> int:  # fmt: skip
        if seq is None:
            seq = self.seq
            self.seq = (self.seq + 1) & 0xFFFF
        payload = pack(seq, self.session, opcode, offset, data, size=size)
        self._send(self.mav.file_transfer_protocol_encode(0, *self.target, payload))
        return seq

    def _reply(self, timeout: float) -> Packet | None:
        """The next reply of our session within ``timeout`` (others are counted, not used)."""
        deadline = time.monotonic() + timeout
        while (remaining := deadline - time.monotonic()) > 0:
            msg = self._recv(remaining)
            if msg is None:
                return None
            p = unpack(msg.payload)
            if p.opcode not in (ACK, NAK):
                continue
            if self.session and p.session != self.session:
                self.foreign_sessions.add(p.session)
                continue
            if p.req_opcode == BURST_READ_FILE and (p.seq + 1 - self.seq) & 0xFFFF < 0x8000:
                # A burst's replies count up from the request's number plus one, and one more
                # ends it when the file does (GCS_FTP.cpp, BurstReadFile: reply.seq_number++
                # per packet, then the EndOfFile NAK), which may come after the read has all
                # its bytes. The next request is numbered past both: one numbered a reply's
                # number less one is taken for a re-request of that reply (GCS_FTP::worker:
                # request.seq_number + 1 == reply.seq_number), answered with it again and
                # never served: TerminateSession after every download went unanswered so,
                # for its 6 attempts (QGC's FTPManager advances its sequence likewise).
                self.seq = (p.seq + 1) & 0xFFFF
            return p
        return None

    def _exchange(self, opcode: int, what: str, offset: int = 0, data: bytes = b"",
                  size: int | None = None) -> Packet:  # fmt: skip
        """Send a request until its reply comes, resending the same sequence number (the
        vehicle answers a re-request with its last reply: GCS_FTP::worker)."""
        seq = self._request(opcode, offset, data, size)
        asked = time.monotonic()
        for attempt in range(self.retries + 1):
            deadline = time.monotonic() + max(self.resend_wait(attempt), self.timeout)
            while (remaining := deadline - time.monotonic()) > 0:
                p = self._reply(remaining)
                if p is None:
                    break
                if p.req_opcode == opcode and p.seq == (seq + 1) & 0xFFFF:
                    if attempt == 0:
                        self._rtt.sample(time.monotonic() - asked)
                    self.last_resent = attempt > 0
                    return p
            if attempt < self.retries:
                self.retry_count += 1
                self._request(opcode, offset, data, size, seq=seq)
        raise self._quiet(what)

    def _quiet(self, what: str) -> FtpQuiet:
        extra = ""
        if self.foreign_sessions:
            extra = (
                f"; it answered for session(s) {sorted(self.foreign_sessions)}, not ours "
                f"({self.session})"
            )
        extra += self.hint()
        return FtpQuiet(f"MAVFTP {what}: no answer after {self.retries + 1} attempts{extra}")

    def _refused(self, p: Packet, what: str) -> FtpError:
        return FtpError(f"MAVFTP {what} refused: {p.nak_text()}", p.data[0] if p.data else 0)

    # Sessions ---------------------------------------------------------------------------------
    def reset(self) -> None:
        """ResetSessions: closes what an earlier client of ours left open (an upload that died
        holds ArduPilot's mission file for 30 s otherwise)."""
        saved, self.session = self.session, 0
        try:
            self._exchange(RESET_SESSIONS, "ResetSessions")
        finally:
            self.session = saved

    def _open(self, opcode: int, path: str) -> Packet:
        """Open ``path`` in a session the vehicle gives us; an open refused as busy is asked
        again after ResetSessions, up to ``retries`` times, waiting longer each time the
        refusal cannot have been our own doing.

        A resent open is not a re-request to ArduPilot: each session-0 request is given a new
        session before the re-request check (GCS_FTP::worker), so when the first copy's ACK
        was lost that copy holds the file and the resend is refused (one upload at a time:
        AP_Filesystem_Mission::open). At 30 % loss each way about three opens in ten are
        refused so; ResetSessions closes the session of that first copy. A refusal without a
        resend is someone else's upload, which frees when it ends or idles out (30 s,
        AP_Filesystem_Mission.cpp IDLE_TIMEOUT_MS)."""
        name = path.encode()
        waits = 0  # refusals that were not our own doing
        resent = False  # the last open was resent: its refusal can be our first copy's doing
        for attempt in range(self.retries + 1):
            if attempt:
                self.retry_count += 1
                self.reset()
                if not resent:
                    self._pause(min(self.resend_wait(0) * 2**waits, self.timeout))
                    waits += 1
            self.session = 0
            self.foreign_sessions.clear()
            p = self._exchange(opcode, f"open {path}", data=name)
            resent = self.last_resent
            if p.opcode == ACK:
                self.session = p.session  # the vehicle allocates it (GCS_FTP::worker)
                return p
            if (p.data[:1] or b"\0")[0] not in OPEN_BUSY:
                raise self._refused(p, f"open {path}")
        raise FtpBusy(
            f"MAVFTP open {path} refused {self.retries + 1} times, our sessions reset before "
            f"each: {p.nak_text()} (another ground station's upload holds the file, or no "
            "session is free)",
            p.data[0] if p.data else 0,
        )

    def _pause(self, seconds: float) -> None:
        """Wait ``seconds``, reading (and dropping) what comes meanwhile: late replies to
        what was answered already; the mission client's receive keeps our heartbeat going."""
        end = time.monotonic() + seconds
        while (remaining := end - time.monotonic()) > 0:
            self._recv(remaining)

    def terminate(self) -> Packet:
        p = self._exchange(TERMINATE_SESSION, "TerminateSession")
        return p

    # Checking ---------------------------------------------------------------------------------
    def crc32(self, path: str) -> int:
        """CalcFileCRC32: the vehicle's CRC-32 of ``path`` (ArduPilot: AP_Filesystem::crc32,
        ``crc_crc32`` from 0 over the file as its file system reads it). A request of its own,
        in a session the vehicle gives it (GCS_FTP::worker), not ours."""
        saved, self.session = self.session, 0
        try:
            p = self._exchange(CALC_FILE_CRC32, f"CRC of {path}", data=path.encode())
        finally:
            self.session = saved
        if p.opcode == NAK:
            raise self._refused(p, f"CRC of {path}")
        if p.size != 4:
            raise FtpError(
                f"the vehicle answered the CRC of {path} with {p.size} data bytes, not 4"
            )
        return int.from_bytes(p.data[:4], "little")

    def read_head(self, path: str, size: int) -> bytes:
        """The first ``size`` bytes (at most one payload) of ``path`` by one ReadFile."""
        if not 0 < size <= DATA_MAX:
            raise ValueError(f"one ReadFile reads 1..{DATA_MAX} bytes, not {size}")
        self._open(OPEN_FILE_RO, path)
        try:
            p = self._exchange(READ_FILE, f"read of {path}", offset=0, size=size)
        finally:
            try:
                self.terminate()
            except FtpError:
                pass  # ArduPilot closes an idle session after 20 s
        if p.opcode == NAK:
            if (p.data[:1] or b"\0")[0] == EOF:
                return b""
            raise self._refused(p, f"read of {path}")
        if p.offset != 0 or p.size > size:
            raise FtpError(
                f"the vehicle answered a read of bytes 0..{size - 1} of {path} with "
                f"{p.size} bytes at {p.offset}"
            )
        return p.data

    # Reading ----------------------------------------------------------------------------------
    def read(
        self,
        path: str,
        length_of: Callable[[bytes], int | None],
        chunks: dict[int, bytes] | None = None,
    ) -> bytes:
        """The whole file at ``path``: a burst read from the start, then the missing ranges
        asked again (ReadFile, several at once), a burst again from where the data stops.

        ``length_of(prefix)`` gives the file's length from its first bytes when the format
        says it (ArduPilot's stat of mission.dat answers a fixed 1 MiB: the header's item
        count is the truth). ``chunks`` (offset -> bytes) keeps what was read across calls so
        a retried read resumes.
        """
        chunks = {} if chunks is None else chunks
        for attempt in range(SESSION_REOPENS + 1):
            self._open(OPEN_FILE_RO, path)
            try:
                return self._read_all(path, length_of, chunks)
            except FtpError as exc:
                # ArduPilot closes a session whose reply could not go for 3 s (a radio whose
                # buffer stayed full: a fade): the read goes on in a new session from what
                # was read.
                if exc.code not in SESSION_LOST or attempt == SESSION_REOPENS:
                    raise
            finally:
                try:
                    self.terminate()
                except FtpError:
                    pass  # ArduPilot closes an idle session after 20 s
        raise AssertionError("unreachable")

    def _backoff(self, start: int, high: int) -> Backoff | None:
        """The back-off of a transfer on a link whose radio does not report its buffer (None
        while one does: its reports pace the transfer, as ArduPilot's GCS_FTP is paced)."""
        return None if self.radio_reports() else Backoff(start, high=high)

    def _round_trip(self) -> float:
        return self._rtt.srtt if self._rtt.srtt is not None else FIRST_WAIT_S

    def _read_all(self, path: str, length_of: Callable[[bytes], int | None],
                  chunks: dict[int, bytes]) -> bytes:  # fmt: skip
        end: int | None = None  # the file's length, once known
        last_progress = time.monotonic()
        window = Window(4, low=1, high=16)
        backoff = self._backoff(4, 16)
        outstanding: dict[int, float] = {}  # offset -> when asked (ReadFile)
        by_seq: dict[int, int] = {}  # the reply's sequence number -> the offset asked
        bursting = False
        bursts = 0
        stall_limit = (self.retries + 1) * self.timeout
        while True:
            head = contiguous(chunks)
            if end is None:
                end = length_of(head)
            if end is not None and len(head) >= end:
                return head[:end]
            now = time.monotonic()
            if now - last_progress > stall_limit:
                raise self._quiet(f"read of {path} stalled at byte {len(head)}")
            if not bursting:
                tail = max((o + len(c) for o, c in chunks.items()), default=0)
                inside = gaps(chunks, tail, len(head))
                if end is None or (not inside and tail < end):
                    # Nothing known missing below the highest byte read: a burst from there
                    # (from the first missing byte while the length is not known).
                    start = len(head) if end is None else tail
                    self.retry_count += int(bool(chunks) or bursts > 0)
                    bursts += 1
                    self._request(BURST_READ_FILE, start, size=DATA_MAX)
                    bursting = True
                else:
                    # Requests a burst has answered since hold no slot of the window.
                    for offset in [o for o in outstanding if o in chunks]:
                        del outstanding[offset]
                    for offset, _ in gaps(chunks, end, len(head)):
                        if self.congested():
                            break
                        asked = outstanding.get(offset)
                        if asked is not None and now - asked < self.resend_wait(0):
                            continue  # its answer can still come
                        slots = window.size if backoff is None else min(window.size, backoff.slots)
                        if asked is None and len(outstanding) >= slots:
                            # No room for a new request; but one whose answer was lost is
                            # asked again below even with the window full (else a window of
                            # lost requests waits for ever: a burst loss stalled the read).
                            continue
                        if asked is not None:
                            window.lost()
                            if backoff is not None:
                                backoff.resent(now, self._round_trip())
                        # Every ReadFile asks again for what a burst lost: a resend.
                        self.retry_count += 1
                        outstanding[offset] = now
                        seq = self._request(READ_FILE, offset, size=DATA_MAX)
                        by_seq[(seq + 1) & 0xFFFF] = offset
            wait = max(self.timeout, self.resend_wait(0)) if bursting else self.resend_wait(0)
            p = self._reply(wait)
            now = time.monotonic()
            if p is None:
                bursting = False  # the burst's end was lost: ask for what is missing
                continue
            if p.req_opcode == READ_FILE:
                asked_offset = by_seq.pop(p.seq, None)
                if asked_offset is None:
                    continue  # an answer to a request already answered
                asked_at = outstanding.pop(asked_offset, None)
            elif p.req_opcode == BURST_READ_FILE:
                asked_offset, asked_at = p.offset, None
            else:
                continue  # a late reply to the open
            if p.opcode == NAK:
                code = p.data[0] if p.data else 0
                if code != EOF:
                    raise self._refused(p, f"read of {path}")
                bursting = bursting and p.req_opcode != BURST_READ_FILE
                if end is None:
                    end = asked_offset if p.req_opcode == READ_FILE else p.offset
                    continue
                if asked_offset < end:
                    raise FtpError(
                        f"{path} ends at byte {asked_offset} (the vehicle's end-of-file), "
                        f"but its own header says {end} bytes"
                    )
                continue
            if p.req_opcode == BURST_READ_FILE and p.burst_complete:
                bursting = False
            if p.opcode != ACK:
                continue
            take(p, chunks, end, path)
            if p.size:
                last_progress = now
            if asked_at is not None:
                self._rtt.sample(now - asked_at)
                window.rtt(now - asked_at)
                window.delivered(now, True)
                if backoff is not None:
                    backoff.answered()

    # Writing ----------------------------------------------------------------------------------
    def write(self, path: str, data: bytes) -> Packet | None:
        """Write ``data`` as the new ``path`` (CreateFile, WriteFile pieces, several out at
        once, each resent until acknowledged by its offset, then TerminateSession). Returns
        the TerminateSession reply (an ACK, or the NAK with which the vehicle refused the file
        when it closed it), or None when that reply never came."""
        self._open(CREATE_FILE, path)
        pieces = {o: data[o : o + DATA_MAX] for o in range(0, len(data), DATA_MAX)}
        acked: set[int] = set()
        sent: dict[int, tuple[float, int]] = {}  # offset -> (when, times)
        # Each piece is a 260-byte frame: WRITE_WINDOW of them fill a SiK radio's 1,850-byte
        # serial buffer, past which it drops what the host writes.
        window = Window(2, low=1, high=WRITE_WINDOW)
        backoff = self._backoff(2, WRITE_WINDOW)
        last_progress = time.monotonic()
        pending = sorted(pieces)
        stall_limit = (self.retries + 1) * self.timeout
        while len(acked) < len(pieces):
            now = time.monotonic()
            if now - last_progress > stall_limit:
                first = min(set(pieces) - acked)
                raise self._quiet(f"write of {path} stalled at byte {first}")
            oldest = min(sent, key=lambda o: sent[o][0], default=None)
            if oldest is not None and now - sent[oldest][0] > self.resend_wait(sent[oldest][1]):
                if not self.congested():
                    self.retry_count += 1
                    window.lost()
                    if backoff is not None:
                        backoff.resent(now, self._round_trip())
                    sent[oldest] = (now, sent[oldest][1] + 1)
                    self._request(WRITE_FILE, oldest, pieces[oldest])
            slots = window.size if backoff is None else min(window.size, backoff.slots)
            while pending and len(sent) < slots and not self.congested():
                o = pending.pop(0)
                sent[o] = (now, 0)
                self._request(WRITE_FILE, o, pieces[o])
            p = self._reply(max(0.005, self.resend_wait(0) / 2))
            now = time.monotonic()
            if p is None or p.req_opcode != WRITE_FILE:
                continue
            if p.opcode == NAK:
                raise self._refused(p, f"write of {path} at byte {p.offset}")
            if p.offset not in pieces:
                raise FtpError(
                    f"the vehicle acknowledged a write at byte {p.offset} of {path}, which "
                    f"was never sent (the file is {len(data)} bytes)"
                )
            if p.offset in acked:
                continue
            acked.add(p.offset)
            limited = len(sent) >= window.size
            when = sent.pop(p.offset, None)
            if when is not None and when[1] == 0:
                self._rtt.sample(now - when[0])
                window.rtt(now - when[0])
                if backoff is not None:
                    backoff.answered()
            window.delivered(now, limited)
            last_progress = now
        try:
            return self.terminate()
        except FtpError:
            return None
