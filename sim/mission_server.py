"""The vehicle side of the MAVLink mission protocol, as ArduPilot and PX4 serve it: the missions
it holds, what it answers, and the rules of both directions (:mod:`sim.mission_receiving` serves
the upload it receives, :mod:`sim.mission_sending` the download it sends).

Each rule follows the autopilot's source, ArduPilot's ``MissionItemProtocol``
(libraries/GCS_MAVLink/MissionItemProtocol.cpp, and ``GCS_MAVLINK::handle_mission_item`` in
GCS_Common.cpp) and PX4's ``MavlinkMissionManager`` (src/modules/mavlink/mavlink_mission.cpp),
where the two differ by the autopilot record's ``protocol`` traits:

* one upload at a time, bound to the ground station that started it. ArduPilot refuses
  another's MISSION_COUNT, download requests and items with MAV_MISSION_DENIED; PX4 answers
  another's MISSION_COUNT MAV_MISSION_ERROR and anything else from it with a status text only
  (``refuses_quietly``). This mock also binds an upload to its sender's network address (both
  autopilots bind a transfer to ids alone) so that two processes with the same ids are caught
  rather than mixed: the same ids from another address are answered as another ground station;
* a MISSION_COUNT from the uploader itself mid-upload: ArduPilot restarts
  (``handle_mission_count``: same sysid/compid, "we will allow them to restart"), whatever
  address it now comes from; PX4, before item 0 has come, asks for item 0 again without reading
  the new count ("looks like our MISSION_REQUEST was lost, try again"), after it answers
  MAV_MISSION_ERROR ("Mission upload busy, already receiving waypoint";
  ``busy_while_receiving``), until its partner cancels
  with MISSION_ACK OPERATION_CANCELLED (``handle_mission_ack``, which checks ids only);
* the vehicle asks for each item in turn (ArduPilot with the legacy MISSION_REQUEST,
  ``queued_request_send``; PX4 with MISSION_REQUEST_INT until it hears the legacy messages,
  ``_int_mode``), again after ``request_resend_s`` of silence (ArduPilot: 1 s plus its radio's
  stream slowdown; PX4: 0.25 s after whatever it sent last), and ends an upload that hears
  nothing for ``transfer_timeout_s`` (ArduPilot 8 s, with MISSION_ACK OPERATION_CANCELLED and
  "Mission upload timeout"; PX4 5 s, with "Operation timeout" only);
* an item other than the one asked for: ArduPilot MAV_MISSION_INVALID_SEQUENCE; PX4 ignores it
  ("Item sequence not expected, ignore item"; ``ignores_items_out_of_sequence``). An item while
  no upload runs: ArduPilot MAV_MISSION_ERROR (``GCS_MAVLINK::handle_mission_item``: "not
  receiving"); PX4 MAV_MISSION_ERROR too ("IGN MISSION_ITEM: No transfer"), except its partner's
  last item again, whose acknowledgement was lost, which is ACCEPTED again
  (``final_item_again``), and an item while it sends a list ("IGN MISSION_ITEM: Busy");
* ArduPilot writes each item into the flown mission as it arrives (``writes_in_place``; here
  while a live flight flies it, sim/live_flight.py); PX4 stores the mission when the last item
  is in;
* ArduPilot always holds its home at seq 0 (an "empty" mission is one item, home); PX4 holds no
  home item (the records' ``home_at_seq0``);
* the items each autopilot takes (:mod:`sim.mission_items`): a refused item ends the upload with
  its result, the stored mission unchanged;
* mission types: MISSION is stored, FENCE and RALLY exist but this vehicle holds none (uploads
  are UNSUPPORTED, downloads are empty, clears succeed), MAV_MISSION_TYPE_ALL clears them all;
  any other type is refused UNSUPPORTED;
* MISSION_CLEAR_ALL while a transfer runs: ArduPilot MAV_MISSION_ERROR; PX4 "IGN CLEAR CMD:
  Busy" only. MISSION_SET_CURRENT while a transfer runs: PX4 "IGN WP CURR CMD: Busy".

Every field is range-checked before it is stored, so nothing is stored that cannot be sent back.
Where this mock adds to an autopilot (the address binding above; ArduPilot ending an upload on
any refusing MISSION_ACK from the uploader's ids, where ``MissionItemProtocol`` reads none; the
abort of two uploads with the same ids interleaving) it says so.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from gcs_planner.sim.mission_items import Peer, check_item, mission_protocol
from gcs_planner.sim.mission_receiving import MissionReceiving, Upload
from gcs_planner.sim.mission_sending import (
    KNOWN_TYPES,
    MAV_MISSION_TYPE_ALL,
    MAV_MISSION_TYPE_FENCE,
    MAV_MISSION_TYPE_RALLY,
    Download,
    MissionSending,
)

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.link.connection import mavlink
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

__all__ = [
    "KNOWN_TYPES",
    "MAV_MISSION_TYPE_ALL",
    "MAV_MISSION_TYPE_FENCE",
    "MAV_MISSION_TYPE_RALLY",
    "Download",
    "MissionServer",
    "Upload",
    "check_item",
    "seq_from_param",
]


def seq_from_param(value: float, count: int) -> int | None:
    """A mission index carried in a float command parameter, or None when it is not one."""
    if not math.isfinite(value) or value != int(value):
        return None
    seq = int(value)
    return seq if 0 <= seq < count else None


class MissionServer(MissionReceiving, MissionSending):
    """Holds the missions and serves the mission protocol.

    ``send`` sends a message; ``statustext`` announces a line; ``lock`` guards the mission and the
    current item (shared with the vehicle that flies them). ``request_timeout`` and
    ``upload_timeout`` (s) default to the autopilot's (``request_resend_s``,
    ``transfer_timeout_s``).
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
        request_timeout: float | None = None,
        upload_timeout: float | None = None,
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
        p = self.protocol
        self.request_timeout = p.request_resend_s if request_timeout is None else request_timeout
        self.upload_timeout = p.transfer_timeout_s if upload_timeout is None else upload_timeout
        self.transfer_timeout = self.upload_timeout
        self.lock = lock
        self.items: list[MissionItem] = []
        self.current_seq = 0
        self.upload: Upload | None = None
        self.download: Download | None = None  # PX4's list being sent (SENDLIST)
        # Who started the last transfer and how far it got (PX4's _transfer_partner and
        # _transfer_seq): its final item sent again after the end is answered ACCEPTED again.
        self.partner: Peer | None = None
        self.transfer_seq = 0
        self.acks_sent: list[int] = []  # MAV_MISSION_RESULT of every MISSION_ACK sent
        self.conflicts = 0  # uploads aborted because two senders with the same ids interleaved
        # PX4 answers in the spelling it last heard, MISSION_ITEM_INT until it hears the legacy
        # one; ArduPilot always asks with the legacy MISSION_REQUEST.
        self.int_mode = p.answers_in_heard_spelling
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
    def mission(self) -> list[MissionItem]:  # type: ignore[override]
        with self.lock:
            return list(self.items)

    @property
    def current(self) -> int:  # type: ignore[override]
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

    def timers(self, now: float) -> None:
        self.download_timers(now)
        self.upload_timers(now)

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
            self.on_ack(msg, peer)
        elif kind == "MISSION_CLEAR_ALL":
            self.on_clear_all(msg, peer)
        elif kind == "MISSION_SET_CURRENT":
            if self.protocol.refuses_quietly and self._busy():
                self.statustext("WPM: IGN WP CURR CMD: Busy", mavlink.MAV_SEVERITY_CRITICAL)
            else:
                self.set_current(int(msg.seq))

    def _busy(self) -> bool:
        return self.upload is not None or self.download is not None

    def on_ack(self, msg: Any, peer: Peer) -> None:
        up = self.upload
        if not self.protocol.refuses_quietly:
            # MissionItemProtocol reads no MISSION_ACK: this mock's ArduPilot ends an upload on
            # any refusal from the uploader's ids, which a restart by MISSION_COUNT makes moot.
            if up is not None and peer == up.peer and msg.type != mavlink.MAV_MISSION_ACCEPTED:
                self.upload = None
            return
        # PX4's handle_mission_ack: only the partner is heard, by ids (a restarted ground
        # station, a new process on a new port, may cancel the upload its predecessor left).
        if peer != self.partner:
            self.statustext("REJ. WP CMD: partner id mismatch", mavlink.MAV_SEVERITY_CRITICAL)
            return
        if self.download_ack(msg, peer) or up is None:
            return
        if msg.type == mavlink.MAV_MISSION_UNSUPPORTED:
            # "INT or float mode is not supported": the request again in the other spelling.
            self.int_mode = not self.int_mode
            self._request(up, time.monotonic())
        elif msg.type == mavlink.MAV_MISSION_OPERATION_CANCELLED:
            self.upload = None

    def on_clear_all(self, msg: Any, peer: Peer) -> None:
        mtype = int(getattr(msg, "mission_type", 0))
        if mtype not in KNOWN_TYPES and mtype != MAV_MISSION_TYPE_ALL:
            self.ack(peer, mavlink.MAV_MISSION_UNSUPPORTED, mtype)
            return
        if self._busy():
            if self.protocol.refuses_quietly:
                self.statustext("WPM: IGN CLEAR CMD: Busy", mavlink.MAV_SEVERITY_CRITICAL)
            else:
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
