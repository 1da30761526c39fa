"""The vehicle side of MAVLink FTP, as ArduPilot serves its mission file ``@MISSION/mission.dat``.

Modelled from libraries/GCS_MAVLink/GCS_FTP.cpp (``GCS_FTP::worker``,
``Session::handle_request``, ``send_reply``) and libraries/AP_Filesystem/
AP_Filesystem_Mission.cpp:

* requests are served one at a time in arrival order; a request that repeats the sequence
  number of the one last answered (request seq + 1 == last reply seq, same session) gets that
  reply again instead of being served twice;
* a request for session 0 claims a session and is given a new id, echoed in every reply;
  ResetSessions closes this ground station's sessions and is always acknowledged;
* OpenFileRO answers the file size from ``stat``, which for mission.dat is a fixed 1 MiB
  (``AP_Filesystem_Mission::stat``): a client learns the length from the file's header.
  Reading builds the file from the mission as it is at the open (ArduPilot reads the items
  live; a mission changed mid-read is not modelled); a read at or past its end is NAK EOF;
* BurstReadFile sends the file from the offset in 239-byte ACKs, each with its offset and
  the sequence number one up, the last (or the EOF NAK after the end) with burst_complete;
  while it runs no other request is served (the worker is inside the burst). On a port
  without flow control each packet is followed by a pause of 3,000 x packet bytes / port
  bytes per second ms, so a burst uses a third of the serial rate; nothing is sent while the
  radio's last RADIO_STATUS has 33 % or less free (``last_txbuf_is_greater(33)``), and a
  session whose reply cannot go for 3 s is closed;
* CreateFile of mission.dat opens an empty buffer (one upload at a time: another is NAK
  FailErrno, the errno one the open did not set), WriteFile writes at its offset and is
  acknowledged with it, a write past the room the vehicle has is NAK FailErrno ENOSPC
  (``AP_Filesystem_Mission::write``: the buffer cannot grow; the room here is the largest
  mission the vehicle stores), and TerminateSession closes the file, which stores
  the mission (``finish_upload``): the header's magic and count must match the bytes, no item
  may be all zeros, every item must be one this vehicle stores, a DO_JUMP target must be
  inside the mission; a failure is NAK FailErrno EINVAL and the mission is left as it was;
* CalcFileCRC32 of mission.dat answers ``crc_crc32`` from 0 over the file as a read of it
  gives it at that moment (``AP_Filesystem::crc32`` opens the file and reads it 64 bytes at a
  time through AP_Filesystem_Mission::read): over the mission stored, not the bytes the last
  upload sent. It is one reply, sent at once like any other: the worker builds the file from
  the stored items without a pause (the time it takes, milliseconds for a thousand items, is
  not modelled);
* the file a read or a CRC sees is built item by item as AP_Mission::get_item gives them
  (:func:`gcs_planner.link.mission_ftp.as_stored`: target 1/1, autocontinue 1, the frame and
  centimetre altitude of a stored Location, ``current`` where the command's id equals the
  current nav index), home at item 0; ArduPilot's narrower storage of some commands' params
  is not modelled;
* any other file is NAK FileNotFound, an unknown opcode NAK UnknownCommand.

PX4 serves FTP on its file system but has no ``@MISSION``: its flavour here answers every open
with FileNotFound, as a path PX4 does not have.
"""

from __future__ import annotations

import struct
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from gcs_planner.sim.mission_items import check_item, mission_protocol
from gcs_planner.sim.mission_server import MissionServer

from gcs_planner.link import ftp
from gcs_planner.link.mission_ftp import (
    CRC_READ,
    HEADER,
    ITEM,
    MAGIC,
    crc32,
    read_call,
    stored_item_bytes,
    xyz_written,
)
from gcs_planner.link.pacing import RadioFlow
from gcs_planner.mission.items import MissionItem

MISSION_FILE = "@MISSION/mission.dat"
STAT_SIZE = 1024 * 1024  # AP_Filesystem_Mission::stat's fixed size
BURST_PACKETS = 2000  # GCS_FTP BurstReadFile: transfer_size
SEND_TIMEOUT_S = 3.0  # FTP_SESSION_TIMEOUT: a reply that cannot go closes the session
EINVAL = 22
ENOSPC = 28
ERRNO_LEFT = 0  # errno as an earlier call left it: a failed open that does not set it
MAV_CMD_DO_JUMP = 177
FRAME_BYTES = 12 + 254  # a MAVLink 2 FILE_TRANSFER_PROTOCOL frame (PAYLOAD_SIZE)


Reader = Callable[[int, int], bytes]  # (offset, size) -> what one read call gives


def mission_reader(items: list[MissionItem], current_nav: int | None) -> Reader:
    """mission.dat as AP_Filesystem_Mission::read gives it from the stored ``items``, one read
    call at a time: the header (magic, data_type, options 0, start 0, count), then each item
    as AP_Mission's get_item builds it into the call's item buffer (x, y, z a command does not
    write are the previous item's in that call: mission_ftp.read_call)."""
    header = HEADER.pack(MAGIC, 0, 0, 0, len(items))
    rendered = [(stored_item_bytes(it, k, current_nav), xyz_written(it.command))
                for k, it in enumerate(items)]  # fmt: skip
    return lambda offset, size: read_call(header, rendered, offset, size)


@dataclass
class _Session:
    sid: int
    peer: tuple[int, int]
    mode: str = ""  # "read" | "write" | ""
    content: Reader = lambda offset, size: b""  # noqa: E731 - the file as it was at the open
    buf: bytearray = field(default_factory=bytearray)  # what was written (write)


@dataclass
class _Burst:
    session: _Session
    reply: ftp.Packet
    offset: int
    sent: int
    next_at: float
    blocked_since: float | None = None


class FtpServer:
    """Serves FILE_TRANSFER_PROTOCOL for a mock vehicle (``handle`` each message, ``timers``
    each turn of its loop: bursts go out there, paced)."""

    def __init__(
        self,
        mav: Any,
        send: Callable[[Any], None],
        missions: MissionServer,
        *,
        flavour: str,
        baud: int = 57600,
        radio: RadioFlow | None = None,
        flow_control: bool = False,
    ) -> None:
        self.mav = mav
        self.send = send
        self.missions = missions
        self.flavour = flavour
        # ArduPilot serves its mission as @MISSION/mission.dat; PX4 has no such file.
        self.serves_mission_file = mission_protocol(flavour).serves_mission_file
        self.radio = radio or RadioFlow()
        # GCS_FTP BurstReadFile: burst_delay_ms = 3000 * pkt_size / bw on a port without flow
        # control (bw = baud / 10 bytes per second).
        self.burst_delay_s = 0.0 if flow_control else 3.0 * FRAME_BYTES / (baud / 10.0)
        self.sessions: dict[tuple[tuple[int, int], int], _Session] = {}
        self._next_sid = 1
        self._queue: deque[tuple[ftp.Packet, tuple[int, int]]] = deque()
        self._burst: _Burst | None = None
        self._last: tuple[tuple[int, int], ftp.Packet] | None = None  # the last reply sent
        self.requests = 0  # requests served (re-requests answered from the last reply too)
        self.writes_stored = 0  # mission files stored
        self.crcs_served = 0  # CalcFileCRC32 answered

    # Receiving --------------------------------------------------------------------------------
    def handle(self, msg: Any, peer: tuple[int, int]) -> None:
        try:
            p = ftp.unpack(msg.payload)
        except ftp.FtpError:
            # GCS_FTP::handle_request: a size over the data is InvalidDataSize.
            raw = bytes(msg.payload)
            seq, session, opcode = struct.unpack_from("<HBB", raw)
            bad = ftp.Packet(seq, session, opcode, 0, 0, 0, 0, b"")
            self._reply(peer, bad, ftp.NAK, data=bytes([3]))
            return
        self._queue.append((p, peer))
        self._serve()

    def _serve(self) -> None:
        while self._queue and self._burst is None:
            p, peer = self._queue.popleft()
            self._one(p, peer)

    # Sending ----------------------------------------------------------------------------------
    def _reply(self, peer: tuple[int, int], req: ftp.Packet, opcode: int, *, data: bytes = b"",
               offset: int = 0, session: int | None = None, seq: int | None = None,
               burst_complete: int = 0) -> ftp.Packet:  # fmt: skip
        sid = req.session if session is None else session
        rseq = (req.seq + 1) & 0xFFFF if seq is None else seq
        payload = ftp.pack(rseq, sid, opcode, offset, data, req_opcode=req.opcode,
                           burst_complete=burst_complete)  # fmt: skip
        reply = ftp.unpack(payload)
        self._last = (peer, reply)
        self._send_payload(peer, payload)
        return reply

    def _send_payload(self, peer: tuple[int, int], payload: list[int]) -> None:
        self.send(self.mav.file_transfer_protocol_encode(0, peer[0], peer[1], payload))

    def _nak(self, peer: tuple[int, int], req: ftp.Packet, code: int, errno: int | None = None,
             **kw: Any) -> None:  # fmt: skip
        data = bytes([code]) if errno is None else bytes([code, errno])
        self._reply(peer, req, ftp.NAK, data=data, **kw)

    # Serving ----------------------------------------------------------------------------------
    def _one(self, p: ftp.Packet, peer: tuple[int, int]) -> None:
        self.requests += 1
        if p.opcode == ftp.RESET_SESSIONS:
            for key in [k for k in self.sessions if k[0] == peer]:
                del self.sessions[key]
            self._reply(peer, p, ftp.ACK)
            return
        if p.opcode in (ftp.ACK, ftp.NAK):
            return
        last = self._last
        if (
            last is not None
            and last[0] == peer
            and last[1].session == p.session
            and (p.seq + 1) & 0xFFFF == last[1].seq
        ):
            # A re-request: its reply was lost. Sent again as it was (GCS_FTP::worker).
            reply = last[1]
            self._send_payload(peer, ftp.pack(reply.seq, reply.session, reply.opcode,
                                              reply.offset, reply.data,
                                              req_opcode=reply.req_opcode,
                                              burst_complete=reply.burst_complete))  # fmt: skip
            return
        s = self.sessions.get((peer, p.session))
        if s is None:
            sid = p.session
            if sid == 0:
                sid = self._next_sid
                self._next_sid = self._next_sid % 255 + 1
            s = self.sessions[(peer, sid)] = _Session(sid, peer)
        op = p.opcode
        name = p.data.rstrip(b"\0").decode("utf-8", "replace")
        if op == ftp.TERMINATE_SESSION:
            ok = self._close(s)
            self.sessions.pop((peer, s.sid), None)
            if ok:
                self._reply(peer, p, ftp.ACK, session=s.sid)
            else:
                self._nak(peer, p, ftp.FAIL_ERRNO, EINVAL, session=s.sid)
        elif op in (ftp.OPEN_FILE_RO, ftp.CREATE_FILE, ftp.OPEN_FILE_WO):
            if s.mode:
                self._nak(peer, p, 1, session=s.sid)  # one file per session
            elif not self.serves_mission_file or name != MISSION_FILE:
                self._nak(peer, p, ftp.FILE_NOT_FOUND, session=s.sid)
            elif op == ftp.OPEN_FILE_RO:
                s.mode, s.content = "read", self._file()
                self._reply(peer, p, ftp.ACK, data=struct.pack("<I", STAT_SIZE), session=s.sid)
            elif any(o.mode == "write" for o in self.sessions.values()):
                # Only one upload at a time: AP_Filesystem_Mission::open returns -1 without
                # setting errno, and GCS_FTP's CreateFile answers FailErrno with whatever errno
                # holds (GCS_FTP::error); ERRNO_LEFT stands for it. Not Fail: a client cannot
                # tell this refusal by its code from any other failed open.
                self._nak(peer, p, ftp.FAIL_ERRNO, ERRNO_LEFT, session=s.sid)
            else:
                s.mode, s.buf = "write", bytearray()
                self._reply(peer, p, ftp.ACK, session=s.sid)
        elif op == ftp.READ_FILE:
            if s.mode != "read":
                self._nak(peer, p, ftp.FILE_NOT_FOUND if not s.mode else 1)
                return
            piece = s.content(p.offset, min(p.size or ftp.DATA_MAX, ftp.DATA_MAX))
            if not piece:
                self._nak(peer, p, ftp.EOF)
            else:
                self._reply(peer, p, ftp.ACK, data=piece, offset=p.offset)
        elif op == ftp.BURST_READ_FILE:
            if s.mode != "read":
                self._nak(peer, p, ftp.FILE_NOT_FOUND if not s.mode else 1)
                return
            request = replace(p, session=s.sid)  # what each packet of the burst answers
            self._burst = _Burst(s, request, p.offset, 0, time.monotonic())
        elif op == ftp.CALC_FILE_CRC32:
            # GCS_FTP::Session::handle_request, CalcFileCRC32: no file need be open; the
            # reply carries the session the worker gave the request.
            if not self.serves_mission_file or name != MISSION_FILE:
                self._nak(peer, p, ftp.FILE_NOT_FOUND, session=s.sid)
                return
            self.crcs_served += 1
            # AP_Filesystem::crc32: the file opened afresh, read CRC_READ bytes at a time.
            read, crc, offset = self._file(), 0, 0
            while piece := read(offset, CRC_READ):
                crc, offset = crc32(piece, crc), offset + len(piece)
            self._reply(peer, p, ftp.ACK, data=struct.pack("<I", crc), session=s.sid)
        elif op == ftp.WRITE_FILE:
            if s.mode != "write":
                self._nak(peer, p, ftp.FILE_NOT_FOUND if not s.mode else 1)
                return
            end = p.offset + len(p.data)
            if end > self._file_room():
                # AP_Filesystem_Mission::write grows its buffer to the write's end or fails for
                # want of memory, errno ENOSPC, which GCS_FTP's WriteFile answers FailErrno.
                self._nak(peer, p, ftp.FAIL_ERRNO, ENOSPC)
                return
            if end > len(s.buf):
                s.buf.extend(bytes(end - len(s.buf)))
            s.buf[p.offset : end] = p.data
            self._reply(peer, p, ftp.ACK, offset=p.offset)
        else:
            self._nak(peer, p, ftp.UNKNOWN_COMMAND)

    def timers(self, now: float) -> None:
        """Send what a burst has due, then serve what waited behind it."""
        b = self._burst
        while b is not None and now >= b.next_at:
            if self.radio.congested():
                b.blocked_since = b.blocked_since or now
                if now - b.blocked_since > SEND_TIMEOUT_S:
                    self.sessions.pop((b.session.peer, b.session.sid), None)
                    self._burst = None
                break
            b.blocked_since = None
            piece = b.session.content(b.offset, ftp.DATA_MAX)  # one read per packet
            seq = (b.reply.seq + 1 + b.sent) & 0xFFFF
            if not piece:
                self._nak(b.session.peer, b.reply, ftp.EOF, offset=b.offset, seq=seq,
                          session=b.session.sid, burst_complete=1)  # fmt: skip
                self._burst = None
                break
            last = b.sent == BURST_PACKETS - 1
            self._reply(b.session.peer, b.reply, ftp.ACK, data=piece, offset=b.offset, seq=seq,
                        session=b.session.sid, burst_complete=int(last))  # fmt: skip
            b.offset += len(piece)
            b.sent += 1
            b.next_at = now + self.burst_delay_s
            if last:
                self._burst = None
                break
            if self.burst_delay_s > 0:
                break
        if self._burst is None:
            self._serve()

    # The mission file -------------------------------------------------------------------------
    def _file_room(self) -> int:
        """The most bytes a mission file being written may hold: ArduPilot's bound is its free
        memory; this vehicle's is the largest mission it stores (its capacity of items), past
        which the file could not be stored anyway."""
        return HEADER.size + self.missions.capacity * ITEM.size

    def _file(self) -> Reader:
        """The file a read or a CRC sees now: built from the stored mission."""
        return mission_reader(self.missions.mission, self.missions.current)

    def _close(self, s: _Session) -> bool:
        if s.mode != "write":
            return True
        items = self._parse(bytes(s.buf))
        if items is None:
            return False
        self.missions.commit(items)
        self.missions.mission_current()
        self.writes_stored += 1
        return True

    def _parse(self, data: bytes) -> list[MissionItem] | None:
        """AP_Filesystem_Mission::finish_upload and finish_upload_mission, whole-mission
        writes (options and start other than 0 are refused here, not modelled)."""
        if len(data) < HEADER.size:
            return None
        magic, dtype, options, start, count = HEADER.unpack_from(data)
        n = (len(data) - HEADER.size) // ITEM.size
        if magic != MAGIC or dtype != 0 or n != count or options or start:
            return None
        if count > self.missions.capacity:
            return None
        items = []
        for i in range(count):
            raw = data[HEADER.size + i * ITEM.size : HEADER.size + (i + 1) * ITEM.size]
            if not any(raw):
                return None  # the client did not fill the whole file
            (p1, p2, p3, p4, x, y, z, _, cmd, _, _, frame, current, auto,
             _) = ITEM.unpack(raw)  # fmt: skip
            item = MissionItem(i, frame, cmd, current, auto, p1, p2, p3, p4, x, y, z)
            if check_item(item, self.flavour) != 0:
                return None
            if cmd == MAV_CMD_DO_JUMP and not 0 < p1 < count:
                return None
            items.append(item)
        return items
