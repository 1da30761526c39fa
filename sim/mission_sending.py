"""The vehicle sending its mission (the ground station's download): MISSION_COUNT for a
MISSION_REQUEST_LIST, then an item for each request, as each autopilot answers them.

ArduPilot keeps no state for a download (libraries/GCS_MAVLink/MissionItemProtocol.cpp):

* ``handle_mission_request_list`` answers the count, MAV_MISSION_DENIED while it receives an
  upload ("reject fetching of points until done or timeout");
* ``handle_mission_request_int`` / ``handle_mission_request`` answer each request on its own,
  whatever came before (DENIED while receiving); a request past the mission is answered with the
  count and MAV_MISSION_ERROR (``MissionItemProtocol_Waypoints::get_item``: "try to educate the
  GCS on the actual size of the mission");
* each item is given back as ``AP_Mission::get_item`` builds it from the stored command (the
  record's ``protocol.stores_locations``): what its mission file holds too.

PX4 sends its list as a transfer of its own, SENDLIST (src/modules/mavlink/mavlink_mission.cpp,
``MavlinkMissionManager``; the record's ``protocol.requests_in_sequence``):

* ``handle_mission_request_list``: from idle, or from the partner of the list being sent, the
  list (re)starts at item 0 and the count goes out; a list sent to its end is over first
  ("maybe_completed": a new list may start without the final MISSION_ACK); otherwise the request
  is ignored with a status text ("Mission download request ignored, already active");
* ``handle_mission_request_both``: only the partner is heard ("REJ. CMD: partner id mismatch");
  in SENDLIST the next item (``_transfer_seq``) or the last one again is answered and any other
  request ends the transfer with MISSION_ACK MAV_MISSION_ERROR ("REJ. CMD: Req. WP was
  unexpected"); a request while idle is ignored without a word ("some OSDs have buggy mission
  protocol implementations"), one while receiving with "REJ. CMD: Busy";
* ``handle_mission_ack``: the partner's MISSION_ACK of the same mission type ends the list,
  whatever its result;
* ``send``: a list that hears nothing for 5 s (MAVLINK_MISSION_PROTOCOL_TIMEOUT_DEFAULT, the
  record's ``transfer_timeout_s``) ends with the status text "Operation timeout" and no ACK;
* the item goes in the spelling of the request (``_int_mode``), ``current`` set on the item the
  mission is at (``send_mission_item``). PX4 sends the ``opaque_id`` of its mission in
  MISSION_COUNT and MISSION_ACK (a CRC-32 of the items, ``crc32_for_mission_item``); the
  MAVLink dialect of the pymavlink this project runs has no such field, so neither side here
  can carry it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from gcs_planner.sim.mission_items import Peer, legacy_item_message

from gcs_planner.aircraft.autopilot import MissionProtocol
from gcs_planner.link.connection import mavlink
from gcs_planner.link.mission_ftp import as_stored, without_leftovers
from gcs_planner.link.protocol import item_to_message
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem

MAV_MISSION_TYPE_FENCE = 1
MAV_MISSION_TYPE_RALLY = 2
MAV_MISSION_TYPE_ALL = 255
KNOWN_TYPES = frozenset({MAV_MISSION_TYPE_MISSION, MAV_MISSION_TYPE_FENCE, MAV_MISSION_TYPE_RALLY})


@dataclass
class Download:
    """PX4's list being sent (SENDLIST): to whom, which list, how long it is, and when its
    partner was last heard."""

    peer: Peer
    mission_type: int
    count: int
    last_receive: float


def given_back(item: MissionItem, seq: int, current: int, protocol: MissionProtocol) -> MissionItem:
    """``item`` (stored at ``seq``) as the vehicle sends it back while ``current`` is the item
    it is at.

    ArduPilot (``stores_locations``): as ``AP_Mission::get_item`` builds it, the same bytes as
    its mission file (``as_stored``: frame as the Location's altitude reference, altitude in
    whole centimetres, autocontinue 1, ``current`` where the command id equals the running nav
    index), into a zeroed packet, so x/y/z the command does not store are 0. PX4: as received,
    ``current`` on the item the mission is at (``send_mission_item``)."""
    if protocol.stores_locations:
        return without_leftovers([as_stored(item, seq, current)])[0]
    return replace(item, current=int(seq == current))


class MissionSending:
    """The download side of :class:`~gcs_planner.sim.mission_server.MissionServer`, which it is
    mixed into: it reads the server's mission, transfer state and senders."""

    # Set by the server.
    mav: Any
    send: Callable[[Any], None]
    statustext: Callable[..., None]
    protocol: MissionProtocol
    transfer_timeout: float
    upload: Any  # the upload being received, or None
    download: Download | None
    partner: Peer | None  # PX4's _transfer_partner: whoever started the last transfer
    transfer_seq: int  # PX4's _transfer_seq, shared by both directions
    downloads_ended = 0  # lists PX4 ended for a request out of sequence (for tests)

    # Provided by the server.
    mission: list[MissionItem]
    current: int
    ack: Callable[..., None]

    def _readable_type(self, msg: Any, peer: Peer) -> int | None:
        """The mission type a download asks for, or None after refusing an unknown one
        (MAV_MISSION_UNSUPPORTED)."""
        mtype = int(getattr(msg, "mission_type", 0))
        if mtype not in KNOWN_TYPES:
            self.ack(peer, mavlink.MAV_MISSION_UNSUPPORTED, mtype)
            return None
        return mtype

    def _items_of(self, mtype: int) -> list[MissionItem]:
        # FENCE and RALLY exist, but this vehicle holds none.
        return self.mission if mtype == MAV_MISSION_TYPE_MISSION else []

    def on_request_list(self, msg: Any, peer: Peer) -> None:
        mtype = self._readable_type(msg, peer)
        if mtype is None:
            return
        count = len(self._items_of(mtype))
        if not self.protocol.requests_in_sequence:
            if self.upload is not None:
                self.ack(peer, mavlink.MAV_MISSION_DENIED, mtype)
                return
            self.send(self.mav.mission_count_encode(peer[0], peer[1], count, mtype))
            return
        down = self.download
        if down is not None and self.transfer_seq == down.count:
            # maybe_completed: the list went out to its end. (PX4 makes the same test in any
            # state, so an upload that has received as many items as the stored mission holds
            # is dropped too, its _transfer_in_progress left set; that is not modelled.)
            self.download = down = None
        restart = down is not None and down.peer == peer and down.mission_type == mtype
        if self.upload is not None or (down is not None and not restart):
            self.statustext("Mission download request ignored, already active")
            return
        self.download = Download(peer, mtype, count, time.monotonic())
        self.partner, self.transfer_seq = peer, 0
        self.send(self.mav.mission_count_encode(peer[0], peer[1], count, mtype))

    def on_request(self, msg: Any, peer: Peer) -> None:
        mtype = self._readable_type(msg, peer)
        if mtype is None:
            return
        if self.protocol.requests_in_sequence:
            self._request_in_sequence(msg, peer, mtype)
            return
        if self.upload is not None and msg.get_type() == "MISSION_REQUEST_INT":
            # Only handle_mission_request_int refuses while receiving; handle_mission_request
            # (the legacy one) goes straight to get_item.
            self.ack(peer, mavlink.MAV_MISSION_DENIED, mtype)
            return
        items = self._items_of(mtype)
        seq = int(msg.seq)
        if not 0 <= seq < len(items):
            if mtype == MAV_MISSION_TYPE_MISSION:
                self.send(self.mav.mission_count_encode(peer[0], peer[1], len(items), mtype))
            self.ack(peer, mavlink.MAV_MISSION_ERROR, mtype)
            return
        self._send_item(msg, peer, items, seq)

    def _request_in_sequence(self, msg: Any, peer: Peer, mtype: int) -> None:
        """PX4's ``handle_mission_request_both``: the next item or the last one again."""
        if peer != self.partner:
            self.statustext("WPM: REJ. CMD: partner id mismatch", mavlink.MAV_SEVERITY_CRITICAL)
            return
        down = self.download
        if down is None:
            if self.upload is not None:
                self.statustext("WPM: REJ. CMD: Busy", mavlink.MAV_SEVERITY_CRITICAL)
            return  # idle: ignored without a word
        if mtype != down.mission_type:
            return  # "Unexpected mission type"
        down.last_receive = time.monotonic()
        seq = int(msg.seq)
        if seq == self.transfer_seq and self.transfer_seq < down.count:
            self.transfer_seq += 1
        elif seq != self.transfer_seq - 1:
            self._end_download(peer, mtype)
            return
        items = self._items_of(mtype)
        if seq < len(items):  # "double check bounds in case of items count changed"
            self._send_item(msg, peer, items, seq)
        else:
            self._end_download(peer, mtype)

    def _end_download(self, peer: Peer, mtype: int) -> None:
        self.download = None
        self.downloads_ended += 1
        self.ack(peer, mavlink.MAV_MISSION_ERROR, mtype)
        self.statustext("WPM: REJ. CMD: Req. WP was unexpected", mavlink.MAV_SEVERITY_CRITICAL)

    def _send_item(self, msg: Any, peer: Peer, items: list[MissionItem], seq: int) -> None:
        """Item ``seq`` in the request's spelling: MISSION_ITEM for MISSION_REQUEST (ArduPilot
        converts, PX4 answers in the mode the request set), else MISSION_ITEM_INT."""
        item = given_back(items[seq], seq, self.current, self.protocol)
        if msg.get_type() == "MISSION_REQUEST":
            self.send(legacy_item_message(self.mav, item, peer))
        else:
            self.send(item_to_message(self.mav, item, peer[0], peer[1]))

    def download_ack(self, msg: Any, peer: Peer) -> bool:
        """PX4's ``handle_mission_ack`` in SENDLIST: the partner's MISSION_ACK of the list's
        type ends it, whatever its result. True when it did."""
        down = self.download
        if down is None or peer != down.peer:
            return False
        if int(getattr(msg, "mission_type", 0)) != down.mission_type:
            return False
        self.download = None
        return True

    def download_timers(self, now: float) -> None:
        """PX4's ``send``: a list that heard nothing for the transfer timeout goes idle."""
        down = self.download
        if down is not None and now - down.last_receive > self.transfer_timeout:
            self.download = None
            self.statustext("Operation timeout", mavlink.MAV_SEVERITY_CRITICAL)
