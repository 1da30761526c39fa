"""The vehicle receiving a mission (the ground station's upload): its MISSION_COUNT, a request
for each item in turn, the items, and the final MISSION_ACK, as each autopilot answers them
(:mod:`sim.mission_server` lists the rules and their sources; ArduPilot:
libraries/GCS_MAVLink/MissionItemProtocol.cpp and ``GCS_MAVLINK::handle_mission_item`` in
GCS_Common.cpp; PX4: ``MavlinkMissionManager`` in src/modules/mavlink/mavlink_mission.cpp).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from gcs_planner.sim.mission_items import Peer, check_item, item_from_wire

from gcs_planner.aircraft.autopilot import MissionProtocol
from gcs_planner.link.connection import mavlink
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem


@dataclass
class Upload:
    """An upload in progress (the vehicle is receiving: ArduPilot's ``receiving``, PX4's
    GETLIST)."""

    peer: Peer
    address: Any  # where its frames came from (a UDP address; None on serial and TCP)
    count: int
    last_receive: float
    last_request: float
    items: list[MissionItem] = field(default_factory=list)

    @property
    def expected(self) -> int:
        return len(self.items)


class MissionReceiving:
    """The upload side of :class:`~gcs_planner.sim.mission_server.MissionServer`, which it is
    mixed into: it stores through the server and answers through its senders."""

    # Set by the server.
    mav: Any
    send: Callable[[Any], None]
    statustext: Callable[..., None]
    protocol: MissionProtocol
    flavour: str
    capacity: int
    request_timeout: float
    upload_timeout: float
    request_slowdown: float
    int_mode: bool
    in_place: bool
    upload: Upload | None
    download: Any  # the list being sent (PX4), or None
    partner: Peer | None
    transfer_seq: int
    conflicts: int

    # Provided by the server.
    ack: Callable[..., None]
    commit: Callable[[list[MissionItem]], None]
    mission_current: Callable[[], None]
    _write_in_place: Callable[[int | None, MissionItem | None, int], None]

    def _request(self, up: Upload, now: float) -> None:
        up.last_request = now
        encode = (
            self.mav.mission_request_int_encode
            if self.int_mode
            else self.mav.mission_request_encode
        )
        self.send(encode(up.peer[0], up.peer[1], up.expected, MAV_MISSION_TYPE_MISSION))

    def upload_timers(self, now: float) -> None:
        up = self.upload
        if up is None:
            return
        if self.protocol.refuses_quietly:
            # PX4's MavlinkMissionManager::send: the request again 0.25 s after the last one,
            # else the operation timeout, ended without a MISSION_ACK.
            if now - up.last_request > self.request_timeout:
                self._request(up, now)
            elif now - up.last_receive > self.upload_timeout:
                self.upload = None
                self.statustext("Operation timeout", mavlink.MAV_SEVERITY_CRITICAL)
            return
        # ArduPilot's MissionItemProtocol::update: the upload timeout first, then the request
        # again after 1 s plus the stream slowdown.
        if now - up.last_receive > self.upload_timeout:
            self.upload = None
            self.ack(up.peer, mavlink.MAV_MISSION_OPERATION_CANCELLED)
            self.statustext("Mission upload timeout", mavlink.MAV_SEVERITY_WARNING)
        elif now - up.last_request > self.request_timeout + self.request_slowdown:
            self._request(up, now)

    def _transfer_owner(self, peer: Peer, address: Any) -> bool:
        up = self.upload
        return up is not None and up.peer == peer and up.address == address

    def on_count(self, msg: Any, peer: Peer, address: Any) -> None:
        mtype = int(getattr(msg, "mission_type", 0))
        if mtype != MAV_MISSION_TYPE_MISSION:
            # FENCE and RALLY: this vehicle has no fence or rally points; others do not exist.
            self.ack(peer, mavlink.MAV_MISSION_UNSUPPORTED, mtype)
            return
        p = self.protocol
        now = time.monotonic()
        if self.download is not None:  # PX4 sending a list: "IGN MISSION_COUNT: Busy"
            self.statustext("WPM: IGN MISSION_COUNT: Busy", mavlink.MAV_SEVERITY_CRITICAL)
            self.ack(peer, mavlink.MAV_MISSION_ERROR, mtype)
            return
        up = self.upload
        if up is not None:
            owner = self._transfer_owner(peer, address)
            if p.busy_while_receiving:  # PX4's handle_mission_count in GETLIST
                up.last_receive = now
                if owner and up.expected == 0:
                    self._request(up, now)  # the same count again: item 0 asked again
                    return
                if owner:
                    self.statustext("WPM: REJ. CMD: Busy", mavlink.MAV_SEVERITY_CRITICAL)
                self.ack(peer, mavlink.MAV_MISSION_ERROR, mtype)
                return
            if not (owner or (p.restarts_upload_by_ids and up.peer == peer)):
                self.ack(peer, mavlink.MAV_MISSION_DENIED, mtype)
                return
        self.upload = None  # the same sender restarts
        self.partner, self.transfer_seq = peer, 0
        count = int(msg.count)
        if count > self.capacity:
            self.ack(peer, mavlink.MAV_MISSION_NO_SPACE)
            self.statustext(f"Only {self.capacity} items are supported")
            return
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
        seq = int(msg.seq)
        if up is None:
            self._item_while_idle(peer, seq)
            return
        p = self.protocol
        owner = self._transfer_owner(peer, address)
        if p.refuses_quietly and not owner:
            self.statustext("REJ. MIS ITEM: partner id mismatch", mavlink.MAV_SEVERITY_CRITICAL)
            return
        if int(getattr(msg, "mission_type", 0)) != MAV_MISSION_TYPE_MISSION:
            self.ack(peer, mavlink.MAV_MISSION_ERROR)  # not the type being received
            return
        item = item_from_wire(msg)
        if p.ignores_items_out_of_sequence:
            up.last_receive = time.monotonic()  # PX4: any item of its partner's is heard
            if seq != up.expected:
                return  # "Item sequence not expected, ignore item"
        elif seq != up.expected:
            if owner and seq == up.expected - 1 and not isinstance(item, int):
                if _differs(item, up.items[seq]):
                    self._abort_interleaved(peer)
                    return
            self.ack(peer, mavlink.MAV_MISSION_INVALID_SEQUENCE)
            return
        if not owner:
            self.ack(peer, mavlink.MAV_MISSION_DENIED)
            return
        self._take_item(up, item, peer, seq)

    def _item_while_idle(self, peer: Peer, seq: int) -> None:
        """An item while no upload runs. PX4 (``handle_mission_item_both``): only its partner is
        answered; the last item of the transfer again (its acknowledgement was lost) is ACCEPTED
        again, any other MAV_MISSION_ERROR. ArduPilot (``GCS_MAVLINK::handle_mission_item``):
        MAV_MISSION_ERROR, "not receiving"."""
        p = self.protocol
        if p.refuses_quietly and peer != self.partner:
            self.statustext("REJ. MIS ITEM: partner id mismatch", mavlink.MAV_SEVERITY_CRITICAL)
            return
        last_again = self.download is None and peer == self.partner and self.transfer_seq == seq + 1
        if p.refuses_quietly and not last_again:
            busy = "Busy" if self.download is not None else "No transfer"
            self.statustext(f"IGN MISSION_ITEM: {busy}", mavlink.MAV_SEVERITY_CRITICAL)
        self.ack(peer, p.final_item_again if last_again else mavlink.MAV_MISSION_ERROR)

    def _abort_interleaved(self, peer: Peer) -> None:
        """The item just stored came again with other contents: two ground stations with the
        same ids are uploading at once (this mock's addition). Neither mission is stored."""
        self.upload = None
        self.conflicts += 1
        self.statustext(
            "Mission upload aborted: two uploads with the same ids interleaved",
            mavlink.MAV_SEVERITY_WARNING,
        )
        self.ack(peer, mavlink.MAV_MISSION_ERROR)

    def _take_item(self, up: Upload, item: MissionItem | int, peer: Peer, seq: int) -> None:
        result = item if isinstance(item, int) else check_item(item, self.flavour)
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
        self.transfer_seq = up.expected
        if self.in_place:
            self._write_in_place(seq, item, up.count)
        if up.expected == up.count:
            self.upload = None
            self.commit(up.items)
            self.ack(peer, mavlink.MAV_MISSION_ACCEPTED)
            self.mission_current()
        else:
            self._request(up, now)


def _differs(a: MissionItem, b: MissionItem) -> bool:
    fields = ("frame", "command", "autocontinue", "param1", "param2", "param3", "param4", "x", "y")
    for name in (*fields, "z"):
        va, vb = getattr(a, name), getattr(b, name)
        if va != vb and not (isinstance(va, float) and math.isnan(va) and math.isnan(vb)):
            return True
    return False
