"""A small vehicle whose mission protocol follows PX4's ``MavlinkMissionManager`` rule by rule
(src/modules/mavlink/mavlink_mission.cpp, PX4 main), speaking MAVLink 2 over UDP on 127.0.0.1
with pymavlink, losing a share of the frames each way. For the client's tests, and kept apart
from the mock vehicle's PX4 flavour (sim/mission_server.py and its parts, which follow the same
source) as a second reading of it: tests/test_mock_px4.py runs one script of exchanges against
both and requires the same answers, so a rule misread in one shows as a difference. This one is
small enough to read in one sitting and has nothing but the mission manager (no address binding,
no capacity, no flight), which is why it is not made a thin use of the mock.

The rules kept (each method names the one it follows):

* download (``handle_mission_request_list``, ``handle_mission_request_both``): a
  MISSION_REQUEST_LIST from idle, or again from the transfer's partner, (re)starts it at item 0
  and answers MISSION_COUNT; a request is answered only for the next item or the last one again,
  any other ends the transfer (idle) with MISSION_ACK MAV_MISSION_ERROR; a request while idle is
  ignored; an item is answered in the spelling of the request (``_int_mode``);
* upload (``handle_mission_count``, ``handle_mission_item_both``): MISSION_COUNT from idle starts
  receiving into the storage not flown and asks for item 0; the same count again before item 0
  asks for it again, after it is MAV_MISSION_ERROR ("busy"); an item out of sequence is ignored;
  the last one stores the mission and answers ACCEPTED; the last item sent again after that is
  ACCEPTED again, any other item while idle MAV_MISSION_ERROR, any item while sending a list
  MAV_MISSION_ERROR;
* timers (``MavlinkMissionManager::send``): while receiving, the request is sent again 0.25 s
  after the last thing sent (MAVLINK_MISSION_RETRY_TIMEOUT_DEFAULT); any transfer with nothing
  received for 5 s (MAVLINK_MISSION_PROTOCOL_TIMEOUT_DEFAULT) goes idle without a word;
* MISSION_ACK from the partner (``handle_mission_ack``): ends a download; CANCELLED ends an
  upload; MISSION_CLEAR_ALL only while idle.
"""

from __future__ import annotations

import random
import socket
import threading
import time
from typing import Any

from gcs_planner.link.connection import mavlink
from gcs_planner.link.protocol import item_from_message
from gcs_planner.mission.items import MissionItem

IDLE, SENDLIST, GETLIST = "idle", "sendlist", "getlist"
RETRY_S = 0.25  # MAVLINK_MISSION_RETRY_TIMEOUT_DEFAULT
PROTOCOL_TIMEOUT_S = 5.0  # MAVLINK_MISSION_PROTOCOL_TIMEOUT_DEFAULT
SYSTEM, COMPONENT = 1, 1
_ACCEPTED, _ERROR = mavlink.MAV_MISSION_ACCEPTED, mavlink.MAV_MISSION_ERROR


class StrictPx4:
    """PX4's mission manager on UDP 127.0.0.1 (``port``), dropping ``loss`` of the frames it
    sends and of those it receives (seeded). ``mission``: what it stores; ``errors_sent``: the
    MISSION_ACK ERRORs it sent; ``ended_downloads``: downloads it ended for a request out of
    sequence."""

    def __init__(self, loss: float = 0.0, seed: int = 0) -> None:
        self.loss = loss
        self.rng = random.Random(seed)
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.01)
        self.port = self.sock.getsockname()[1]
        self.mav = mavlink.MAVLink(None, srcSystem=SYSTEM, srcComponent=COMPONENT)
        self.parser = mavlink.MAVLink(None)
        self.parser.robust_parsing = True
        self.peer: Any = None
        self.mission: list[MissionItem] = []
        self.receiving: dict[int, MissionItem] = {}
        self.state = IDLE
        self.int_mode = True
        self.transfer_seq = 0
        self.transfer_count = 0
        self.partner = (0, 0)
        self.time_last_sent = 0.0
        self.time_last_recv = 0.0
        self.errors_sent = 0
        self.ended_downloads = 0
        self._heartbeat_at = 0.0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> StrictPx4:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.sock.close()

    # The wire ---------------------------------------------------------------------------------
    def _send(self, msg: Any) -> None:
        if self.peer is None or self.rng.random() < self.loss:
            return
        self.sock.sendto(bytes(msg.pack(self.mav)), self.peer)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                data, addr = self.sock.recvfrom(65535)
            except (TimeoutError, OSError):
                data, addr = b"", None
            now = time.monotonic()
            if addr is not None:
                self.peer = addr
                for msg in self.parser.parse_buffer(data) or []:
                    if msg.get_type() != "BAD_DATA" and self.rng.random() >= self.loss:
                        self._handle(msg, now)
            self._timers(now)

    def _timers(self, now: float) -> None:
        """``MavlinkMissionManager::send``: the heartbeat, the request resent while receiving,
        the operation timeout."""
        if now - self._heartbeat_at >= 1.0:
            self._heartbeat_at = now
            self._send(self.mav.heartbeat_encode(mavlink.MAV_TYPE_FIXED_WING,
                                                 mavlink.MAV_AUTOPILOT_PX4, 0, 0, 4))  # fmt: skip
        if self.state == GETLIST and now - self.time_last_sent > RETRY_S:
            self._send_request(self.transfer_seq, now)
        elif self.state != IDLE and now - self.time_last_recv > PROTOCOL_TIMEOUT_S:
            self.state = IDLE

    def _ack(self, to: tuple[int, int], result: int) -> None:
        self.errors_sent += result == _ERROR
        self._send(self.mav.mission_ack_encode(*to, result, 0))

    def _send_request(self, seq: int, now: float) -> None:
        self.time_last_sent = now
        mav = self.mav
        encode = mav.mission_request_int_encode if self.int_mode else mav.mission_request_encode
        self._send(encode(*self.partner, seq, 0))

    def _send_item(self, seq: int, now: float) -> None:
        self.time_last_sent = now
        it = self.mission[seq]
        if self.int_mode:
            encode, x, y = self.mav.mission_item_int_encode, int(it.x), int(it.y)
        else:
            encode, x, y = self.mav.mission_item_encode, it.x / 1e7, it.y / 1e7
        self._send(encode(*self.partner, seq, it.frame, it.command, 0, it.autocontinue,
                          it.param1, it.param2, it.param3, it.param4, x, y, it.z, 0))  # fmt: skip

    # The mission manager ----------------------------------------------------------------------
    def _handle(self, msg: Any, now: float) -> None:
        kind = msg.get_type()
        if kind == "HEARTBEAT":
            return
        ts, tc = getattr(msg, "target_system", None), getattr(msg, "target_component", None)
        # CHECK_SYSID_COMPID_MISSION
        if ts != SYSTEM or tc not in (COMPONENT, mavlink.MAV_COMP_ID_MISSIONPLANNER, 0):
            return
        sender = (msg.get_srcSystem(), msg.get_srcComponent())
        handler = {
            "MISSION_REQUEST_LIST": self._request_list,
            "MISSION_REQUEST": self._request,
            "MISSION_REQUEST_INT": self._request,
            "MISSION_COUNT": self._count,
            "MISSION_ITEM": self._item,
            "MISSION_ITEM_INT": self._item,
            "MISSION_ACK": self._mission_ack,
            "MISSION_CLEAR_ALL": self._clear_all,
        }.get(kind)
        if handler is not None and getattr(msg, "mission_type", 0) == 0:
            handler(msg, sender, now)

    def _request_list(self, msg: Any, sender: tuple[int, int], now: float) -> None:
        """``handle_mission_request_list``."""
        if self.transfer_seq == len(self.mission):
            self.state = IDLE  # "maybe_completed": a new list may start without the final ACK
        if self.state == IDLE or (self.state == SENDLIST and sender == self.partner):
            self.time_last_recv = now
            self.state, self.transfer_seq, self.partner = SENDLIST, 0, sender
            self.transfer_count = len(self.mission)
            self.time_last_sent = now
            self._send(self.mav.mission_count_encode(*sender, self.transfer_count, 0))

    def _request(self, msg: Any, sender: tuple[int, int], now: float) -> None:
        """``handle_mission_request`` / ``_int`` and ``handle_mission_request_both``."""
        self.int_mode = msg.get_type() == "MISSION_REQUEST_INT"
        if sender != self.partner or self.state != SENDLIST:
            return  # idle: silently ignored; receiving: "busy", a status text only
        self.time_last_recv = now
        seq = int(msg.seq)
        if seq == self.transfer_seq and self.transfer_seq < self.transfer_count:
            self.transfer_seq += 1
        elif seq != self.transfer_seq - 1:
            self.state = IDLE
            self.ended_downloads += 1
            self._ack(self.partner, _ERROR)  # "REJ. CMD: Req. WP was unexpected"
            return
        if seq < len(self.mission):
            self._send_item(seq, now)
        else:
            self.state = IDLE
            self._ack(self.partner, _ERROR)

    def _count(self, msg: Any, sender: tuple[int, int], now: float) -> None:
        """``handle_mission_count``."""
        if self.state == IDLE:
            self.time_last_recv = now
            self.partner, self.receiving = sender, {}
            if msg.count == 0:
                self.mission = []
                self._ack(sender, _ACCEPTED)
                return
            self.state, self.transfer_seq, self.transfer_count = GETLIST, 0, int(msg.count)
        elif self.state == GETLIST:
            self.time_last_recv = now
            if sender != self.partner or self.transfer_seq != 0:
                self._ack(sender, _ERROR)  # "Mission upload busy, already receiving waypoint"
                return
        else:
            self._ack(sender, _ERROR)  # "IGN MISSION_COUNT: Busy"
            return
        self._send_request(self.transfer_seq, now)

    def _item(self, msg: Any, sender: tuple[int, int], now: float) -> None:
        """``handle_mission_item`` / ``_int`` and ``handle_mission_item_both``."""
        self.int_mode = msg.get_type() == "MISSION_ITEM_INT"
        if sender != self.partner:
            return  # "REJ. MIS ITEM: partner id mismatch"
        if self.state == IDLE:
            last = self.transfer_seq == int(msg.seq) + 1
            self._ack(self.partner, _ACCEPTED if last else _ERROR)
            return
        if self.state != GETLIST:
            self._ack(self.partner, _ERROR)  # "IGN MISSION_ITEM: Busy"
            return
        self.time_last_recv = now
        if int(msg.seq) != self.transfer_seq:
            return  # "Item sequence not expected, ignore item"
        self.receiving[self.transfer_seq] = item_from_message(msg)
        self.transfer_seq += 1
        if self.transfer_seq == self.transfer_count:
            self.mission = [self.receiving[k] for k in range(self.transfer_count)]
            self.state = IDLE
            self._ack(self.partner, _ACCEPTED)
        else:
            self._send_request(self.transfer_seq, now)

    def _mission_ack(self, msg: Any, sender: tuple[int, int], now: float) -> None:
        """``handle_mission_ack``."""
        if sender != self.partner:
            return
        if self.state == SENDLIST:
            self.time_last_recv = now
            self.state = IDLE
        elif self.state == GETLIST and msg.type == mavlink.MAV_MISSION_UNSUPPORTED:
            self.int_mode = not self.int_mode
            self._send_request(self.transfer_seq, now)
        elif self.state == GETLIST and msg.type == mavlink.MAV_MISSION_OPERATION_CANCELLED:
            self.state = IDLE

    def _clear_all(self, msg: Any, sender: tuple[int, int], now: float) -> None:
        """``handle_mission_clear_all``."""
        if self.state == IDLE:
            self.time_last_recv = now
            self.mission = []
            self._ack(sender, _ACCEPTED)
