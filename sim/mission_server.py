"""The vehicle side of the MAVLink mission protocol, as ArduPilot and PX4 serve it.

What a real autopilot does, modelled from ArduPilot's ``MissionItemProtocol`` and PX4's
``MavlinkMissionManager``:

* one transfer at a time, bound to the ground station that started it: anyone else (other
  system/component ids, or the same ids from another network address) is DENIED until it ends.
  The address is this mock's addition (both autopilots bind a transfer to ids alone), kept so
  that two processes with the same ids are caught rather than mixed;
* a MISSION_COUNT from the uploader itself mid-transfer, as a ground station restarting after
  its upload died: ArduPilot restarts (``MissionItemProtocol::handle_mission_count`` in
  libraries/GCS_MAVLink/MissionItemProtocol.cpp: same sysid/compid, "we will allow them to
  restart"), whatever address it now comes from, since ArduPilot cannot tell; PX4 restarts only
  while it still waits for item 0, and otherwise answers MAV_MISSION_ERROR "Mission upload
  busy" (``MavlinkMissionManager::handle_mission_count``, src/modules/mavlink/
  mavlink_mission.cpp) until the ground station cancels it with MISSION_ACK
  OPERATION_CANCELLED from the same ids (``handle_mission_ack``, which checks ids, not where
  the message came from). MissionItemProtocol.cpp has no handler for a ground station's
  MISSION_ACK; this mock's ArduPilot ends an upload on any refusal from the uploader's ids, as
  it did before, which a restart by MISSION_COUNT makes moot;
* an upload is a restartable series of requests: ArduPilot asks with the legacy MISSION_REQUEST;
  PX4 with MISSION_REQUEST_INT until a ground station speaks the legacy messages to it, then with
  MISSION_REQUEST (its ``_int_mode``); an item not received within ``request_timeout`` is asked for
  again and an upload silent for ``upload_timeout`` is cancelled;
* a MISSION_REQUEST is answered with the legacy float MISSION_ITEM and a MISSION_REQUEST_INT
  with MISSION_ITEM_INT, as both autopilots answer;
* ArduPilot always holds its home at seq 0 (an "empty" mission is one item, home); PX4 holds no
  home item (the autopilot records' ``home_at_seq0``);
* the items each autopilot takes: ArduPilot stores any command of its list; PX4 takes only the
  commands ``MavlinkMissionManager::parse_mavlink_mission_item`` maps (global-frame NAV items,
  frame-MISSION DO/CONDITION items; mavlink_mission.cpp), and refuses the whole upload with
  MAV_MISSION_UNSUPPORTED at the first item it does not: NAV_LOITER_TURNS among them, which PX4
  has no mission item for (the exporter writes PX4 helices as NAV_LOITER_TO_ALT);
* mission types: MISSION is stored, FENCE and RALLY exist but this vehicle holds none (uploads
  are UNSUPPORTED, downloads are empty, clears succeed), MAV_MISSION_TYPE_ALL clears them all;
  any other type is refused UNSUPPORTED.

Every field is range-checked before it is stored, so nothing is stored that cannot be sent back.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from gcs_planner.sim.mission_items import (
    Peer,
    check_item,
    item_from_wire,
    legacy_item_message,
    mission_protocol,
)

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.link.connection import mavlink
from gcs_planner.link.protocol import item_to_message
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

MAV_MISSION_TYPE_FENCE = 1
MAV_MISSION_TYPE_RALLY = 2
MAV_MISSION_TYPE_ALL = 255
KNOWN_TYPES = frozenset({MAV_MISSION_TYPE_MISSION, MAV_MISSION_TYPE_FENCE, MAV_MISSION_TYPE_RALLY})


@dataclass
class Upload:
    """An upload in progress (the vehicle is receiving)."""

    peer: Peer
    address: Any  # where its frames came from (a UDP address; None on serial and TCP)
    count: int
    last_receive: float
    last_request: float
    items: list[MissionItem] = field(default_factory=list)

    @property
    def expected(self) -> int:
        return len(self.items)


def seq_from_param(value: float, count: int) -> int | None:
    """A mission index carried in a float command parameter, or None when it is not one."""
    if not math.isfinite(value) or value != int(value):
        return None
    seq = int(value)
    return seq if 0 <= seq < count else None


class MissionServer:
    """Holds the missions and serves the mission protocol.

    ``send`` sends a message; ``statustext`` announces a line; ``lock`` guards the mission and the
    current item (shared with the vehicle that flies them).
    """

    HANDLED = (
        "MISSION_COUNT",
        "MISSION_ITEM_INT",
        "MISSION_ITEM",
        "MISSION_REQUEST_LIST",
        "MISSION_REQUEST_INT",
        "MISSION_REQUEST",
        "MISSION_ACK",
        "MISSION_CLEAR_ALL",
        "MISSION_SET_CURRENT",
    )

    def __init__(
        self,
        mav: Any,
        send: Callable[[Any], None],
        statustext: Callable[..., None],
        *,
        flavour: str,
        capacity: int,
        home: tuple[int, int, float],
        request_timeout: float,
        upload_timeout: float,
        lock: threading.Lock,
    ) -> None:
        self.mav = mav
        self.send = send
        self.statustext = statustext
        self.flavour = flavour
        self.home_at_seq0 = autopilot_for(flavour).home_at_seq0
        self.protocol = mission_protocol(flavour)
        self.capacity = capacity
        self.home = home
        self.request_timeout = request_timeout
        self.upload_timeout = upload_timeout
        self.lock = lock
        self.items: list[MissionItem] = []
        self.current_seq = 0
        self.upload: Upload | None = None
        # (peer, count) of the last upload completed: its final item may come again when the
        # ground station missed the acknowledgement, and is answered with it again.
        self.completed: tuple[Peer, int] | None = None
        self.acks_sent: list[int] = []  # MAV_MISSION_RESULT of every MISSION_ACK sent
        self.conflicts = 0  # uploads aborted because two senders with the same ids interleaved
        # PX4 answers in the spelling it last heard, MISSION_ITEM_INT until it hears the legacy
        # one; ArduPilot always asks with the legacy MISSION_REQUEST.
        self.int_mode = self.protocol.answers_in_heard_spelling
        self.request_slowdown = 0.0  # ArduPilot's stream slowdown from its radio's reports
        # While a live flight flies the mission (sim/live_vehicle.py): ``listener`` hears every
        # change of the stored mission ("stored", items) and every item set current by the
        # ground station ("current", seq); ``in_flight`` keeps the current item across an
        # upload (the autopilot flies on); ``in_place`` writes each item as it arrives, as
        # ArduPilot does (sim/live_flight.py), instead of storing the mission when complete.
        self.listener: Callable[[tuple[str, Any]], None] | None = None
        self.in_flight = False
        self.in_place = False
        self.commit([])

    # What it holds ----------------------------------------------------------------------------
    @property
    def mission(self) -> list[MissionItem]:
        with self.lock:
            return list(self.items)

    @property
    def current(self) -> int:
        with self.lock:
            return self.current_seq

    def commit(self, items: list[MissionItem]) -> None:
        items = [replace(it, current=0, seq=k) for k, it in enumerate(items)]
        if self.home_at_seq0:
            # ArduPilot always holds its own home at seq 0, whatever was sent there.
            lat, lon, alt = self.home
            home = MissionItem(0, 0, 16, 0, 1, 0.0, 0.0, 0.0, 0.0, lat, lon, alt)
            items = [home, *items[1:]]
        with self.lock:
            self.items = items
            if not (self.in_flight and self.current_seq < len(items)):
                self.current_seq = 1 if self.home_at_seq0 and len(items) > 1 else 0
        self._tell("stored", list(items))

    def _tell(self, what: str, value: Any) -> None:
        if self.listener is not None:
            self.listener((what, value))

    def _write_in_place(self, seq: int | None, item: MissionItem | None, count: int) -> None:
        """ArduPilot's stored mission during an upload: truncated to the new count when the
        count arrives (``MissionItemProtocol::handle_mission_count`` calls ``truncate``), each
        item written as it arrives (``replace_item`` / ``append_item``); home stays at 0."""
        with self.lock:
            items = self.items[: max(count, 1)]
            if seq is not None and item is not None and seq > 0:
                stored = replace(item, current=0, seq=seq)
                if seq < len(items):
                    items[seq] = stored
                else:
                    items.append(stored)
            self.items = items
        self._tell("stored", list(items))

    # Sending ----------------------------------------------------------------------------------
    def ack(self, peer: Peer, result: int, mission_type: int = MAV_MISSION_TYPE_MISSION) -> None:
        self.acks_sent.append(result)
        self.send(self.mav.mission_ack_encode(peer[0], peer[1], result, mission_type))

    def mission_current(self) -> None:
        with self.lock:
            seq, total = self.current_seq, len(self.items)
        self.send(self.mav.mission_current_encode(seq, total))

    def _request(self, up: Upload, now: float) -> None:
        up.last_request = now
        encode = (
            self.mav.mission_request_int_encode
            if self.int_mode
            else self.mav.mission_request_encode
        )
        self.send(encode(up.peer[0], up.peer[1], up.expected, MAV_MISSION_TYPE_MISSION))

    def timers(self, now: float) -> None:
        up = self.upload
        if up is None:
            return
        if now - up.last_receive > self.upload_timeout:
            self.upload = None
            self.ack(up.peer, mavlink.MAV_MISSION_OPERATION_CANCELLED)
            self.statustext("Mission upload timed out", mavlink.MAV_SEVERITY_WARNING)
        elif now - up.last_request > self.request_timeout + self.request_slowdown:
            self._request(up, now)

    # Handlers ---------------------------------------------------------------------------------
    def handle(self, msg: Any, peer: Peer, address: Any = None) -> None:
        kind = msg.get_type()
        heard_spelling = self.protocol.answers_in_heard_spelling
        if heard_spelling and kind in ("MISSION_ITEM", "MISSION_REQUEST"):
            self.int_mode = False
        elif heard_spelling and kind in ("MISSION_ITEM_INT", "MISSION_REQUEST_INT"):
            self.int_mode = True
        if kind in ("MISSION_ITEM_INT", "MISSION_ITEM"):
            self.on_item(msg, peer, address)
        elif kind == "MISSION_COUNT":
            self.on_count(msg, peer, address)
        elif kind == "MISSION_REQUEST_LIST":
            self.on_request_list(msg, peer)
        elif kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            self.on_request(msg, peer)
        elif kind == "MISSION_ACK":
            up = self.upload
            cancels = (
                msg.type == mavlink.MAV_MISSION_OPERATION_CANCELLED
                if self.protocol.cancelled_only_by_cancel
                else msg.type != mavlink.MAV_MISSION_ACCEPTED
            )
            if up is not None and peer == up.peer and cancels:
                # By ids alone, as PX4 checks: a restarted ground station (a new process on a
                # new port) may cancel the upload its predecessor left.
                self.upload = None
        elif kind == "MISSION_CLEAR_ALL":
            self.on_clear_all(msg, peer)
        elif kind == "MISSION_SET_CURRENT":
            self.set_current(int(msg.seq))

    def _transfer_owner(self, peer: Peer, address: Any) -> bool:
        up = self.upload
        return up is not None and up.peer == peer and up.address == address

    def on_count(self, msg: Any, peer: Peer, address: Any) -> None:
        mtype = int(getattr(msg, "mission_type", 0))
        if mtype != MAV_MISSION_TYPE_MISSION:
            # FENCE and RALLY: this vehicle has no fence or rally points; others do not exist.
            self.ack(peer, mavlink.MAV_MISSION_UNSUPPORTED, mtype)
            return
        up = self.upload
        if up is not None:
            restart_by_ids = self.protocol.restarts_upload_by_ids and up.peer == peer
            if not (restart_by_ids or self._transfer_owner(peer, address)):
                self.ack(peer, mavlink.MAV_MISSION_DENIED, mtype)
                return
            if self.protocol.busy_while_receiving and up.expected > 0:
                self.statustext("Mission upload busy", mavlink.MAV_SEVERITY_CRITICAL)
                self.ack(peer, mavlink.MAV_MISSION_ERROR, mtype)
                return
        self.upload = None  # the same sender restarts
        self.completed = None
        count = int(msg.count)
        if count > self.capacity:
            self.ack(peer, mavlink.MAV_MISSION_NO_SPACE)
            self.statustext(f"Only {self.capacity} items are supported")
            return
        now = time.monotonic()
        if count == 0:
            self.commit([])
            self.ack(peer, mavlink.MAV_MISSION_ACCEPTED)
            return
        self.upload = Upload(peer, address, count, now, now)
        if self.in_place:
            self._write_in_place(None, None, count)
        self._request(self.upload, now)

    def on_item(self, msg: Any, peer: Peer, address: Any) -> None:
        up = self.upload
        mtype = int(getattr(msg, "mission_type", 0))
        if up is None or mtype != MAV_MISSION_TYPE_MISSION:
            if up is None and self.completed == (peer, int(msg.seq) + 1):
                # The final item resent: the acknowledgement was lost. PX4 answers ACCEPTED
                # again (handle_mission_item_both, idle with _transfer_seq == seq + 1);
                # ArduPilot, no longer receiving, answers any item with MAV_MISSION_ERROR
                # (GCS_MAVLINK::handle_mission_item in GCS_Common.cpp).
                self.ack(peer, self.protocol.final_item_again)
            return  # otherwise a late copy of an item from a finished transfer
        if not self._transfer_owner(peer, address):
            self.ack(peer, mavlink.MAV_MISSION_DENIED)
            return
        item = item_from_wire(msg)
        result = item if isinstance(item, int) else check_item(item, self.flavour)
        seq = int(msg.seq)
        if seq != up.expected:
            if (
                seq == up.expected - 1
                and not isinstance(item, int)
                and _differs(item, up.items[seq])
            ):
                # The item just stored came again with other contents: two ground stations
                # with the same ids are uploading at once. Neither mission is stored.
                self.upload = None
                self.conflicts += 1
                self.statustext(
                    "Mission upload aborted: two uploads with the same ids interleaved",
                    mavlink.MAV_SEVERITY_WARNING,
                )
                self.ack(peer, mavlink.MAV_MISSION_ERROR)
                return
            self.ack(peer, mavlink.MAV_MISSION_INVALID_SEQUENCE)
            return
        if result != mavlink.MAV_MISSION_ACCEPTED:
            # The whole upload ends here, the stored mission unchanged (both autopilots: PX4's
            # handle_mission_item switches to idle after the refusing MISSION_ACK).
            self.upload = None
            if result == mavlink.MAV_MISSION_UNSUPPORTED and not isinstance(item, int):
                self.statustext(f"Mission item {seq}: command {item.command} not supported")
            self.ack(peer, result)
            return
        assert isinstance(item, MissionItem)
        now = time.monotonic()
        up.items.append(item)
        up.last_receive = now
        if self.in_place:
            self._write_in_place(seq, item, up.count)
        if up.expected == up.count:
            self.upload = None
            self.completed = (peer, up.count)
            self.commit(up.items)
            self.ack(peer, mavlink.MAV_MISSION_ACCEPTED)
            self.mission_current()
        else:
            self._request(up, now)

    def _readable_type(self, msg: Any, peer: Peer) -> int | None:
        """The mission type a download asks for, or None after refusing it: unknown types are
        unsupported, and nothing is read while an upload is under way."""
        mtype = int(getattr(msg, "mission_type", 0))
        if mtype not in KNOWN_TYPES:
            self.ack(peer, mavlink.MAV_MISSION_UNSUPPORTED, mtype)
            return None
        if self.upload is not None:
            self.ack(peer, mavlink.MAV_MISSION_DENIED, mtype)
            return None
        return mtype

    def on_request_list(self, msg: Any, peer: Peer) -> None:
        mtype = self._readable_type(msg, peer)
        if mtype is None:
            return
        count = len(self.mission) if mtype == MAV_MISSION_TYPE_MISSION else 0
        self.send(self.mav.mission_count_encode(peer[0], peer[1], count, mtype))

    def on_request(self, msg: Any, peer: Peer) -> None:
        mtype = self._readable_type(msg, peer)
        if mtype is None:
            return
        mission = self.mission if mtype == MAV_MISSION_TYPE_MISSION else []
        seq = int(msg.seq)
        if not 0 <= seq < len(mission):
            self.ack(peer, mavlink.MAV_MISSION_INVALID_SEQUENCE, mtype)
            return
        item = mission[seq]
        if seq == self.current:
            item = replace(item, current=1)
        if msg.get_type() == "MISSION_REQUEST":
            self.send(legacy_item_message(self.mav, item, peer))
        else:
            self.send(item_to_message(self.mav, item, peer[0], peer[1]))

    def on_clear_all(self, msg: Any, peer: Peer) -> None:
        mtype = int(getattr(msg, "mission_type", 0))
        if mtype not in KNOWN_TYPES and mtype != MAV_MISSION_TYPE_ALL:
            self.ack(peer, mavlink.MAV_MISSION_UNSUPPORTED, mtype)
            return
        if self.upload is not None:
            self.ack(peer, mavlink.MAV_MISSION_ERROR, mtype)
            return
        if mtype in (MAV_MISSION_TYPE_MISSION, MAV_MISSION_TYPE_ALL):
            self.commit([])
        self.ack(peer, mavlink.MAV_MISSION_ACCEPTED, mtype)

    def set_current(self, seq: int) -> bool:
        with self.lock:
            ok = 0 <= seq < len(self.items)
            if ok:
                self.current_seq = seq
        if ok:
            self._tell("current", seq)
            self.mission_current()
        else:
            self.statustext(f"Set current item {seq} failed: no such item")
        return ok


def _differs(a: MissionItem, b: MissionItem) -> bool:
    fields = ("frame", "command", "autocontinue", "param1", "param2", "param3", "param4", "x", "y")
    for name in (*fields, "z"):
        va, vb = getattr(a, name), getattr(b, name)
        if va != vb and not (isinstance(va, float) and math.isnan(va) and math.isnan(vb)):
            return True
    return False
