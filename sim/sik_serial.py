"""One SiK radio and its host: the frames waiting in the radio's serial buffers, its link
figures (rssi, noise, the other radio's as last reported), the UDP socket its host connects to
as it would plug into the radio's serial port; and the counts of what the pair did
(:mod:`sim.radio` describes the whole model).
"""

from __future__ import annotations

import socket
from collections import deque
from dataclasses import dataclass, field
from typing import Any

# RSSI in SiK's units (about 1.9 per dBm plus an offset: ardupilot_wiki, "SiK Radio - Advanced
# Configuration"): a good link near 180, the noise floor near 40.
RSSI_GOOD = 180
RSSI_BAD = 70
NOISE = 40


@dataclass
class RadioCounts:
    """What the pair did, for tests and the benchmark."""

    packets: int = 0
    packets_lost: int = 0
    yields: int = 0
    frames_to_vehicle: int = 0
    frames_to_ground: int = 0
    serial_in_drops: int = 0  # frames a full serial-in buffer refused
    serial_out_drops: int = 0  # frames a full serial-out buffer refused
    broken_frames: int = 0  # frames that lost a piece in the air
    statuses: int = 0  # RADIO_STATUS written to the hosts
    data_air_s: float = 0.0  # air time of packets that carried data


class FramePiece:
    """A frame in a serial-in buffer: how much of it has gone to the air, and whether a packet
    carrying part of it was lost."""

    __slots__ = ("frame", "sent", "broken")

    def __init__(self, frame: bytes) -> None:
        self.frame = frame
        self.sent = 0
        self.broken = False


@dataclass
class RadioEnd:
    """One radio and its host: the serial line in, the buffers, the serial line out."""

    name: str
    sock: socket.socket
    peer: Any  # the host's UDP address (None until heard, for a listening end)
    listening: bool
    line_in_free: float = 0.0
    serial_in: deque[FramePiece] = field(default_factory=deque)
    serial_in_used: int = 0
    serial_out: deque[bytes] = field(default_factory=deque)
    serial_out_used: int = 0
    line_out_busy: bool = False
    yielded: bool = False
    bonus: bool = False
    stats_due: bool = True
    rssi: float = 0.0
    noise: float = float(NOISE)
    remote_rssi: int = 0
    remote_noise: int = 0
    rx_errors: int = 0
    heard_at: float = -1e9  # when this radio last received a packet
    heartbeat_seen: bool = False


def is_heartbeat(frame: bytes) -> bool:
    """SiK's ``check_heartbeat``: a MAVLink 1 or 2 frame whose message id is 0."""
    if len(frame) >= 10 and frame[0] == 0xFD:
        return frame[7] == 0 and frame[8] == 0 and frame[9] == 0
    return len(frame) >= 6 and frame[0] == 0xFE and frame[5] == 0


def udp_endpoint(text: str) -> tuple[socket.socket, Any, bool]:
    """A UDP socket for ``udpin:HOST:PORT`` (bound there; answers the last sender) or
    ``udpout:HOST:PORT`` (sends there from a free port)."""
    scheme, _, rest = text.partition(":")
    host, _, port_text = rest.rpartition(":")
    if scheme not in ("udpin", "udpout") or not host or not port_text.isdigit():
        raise ValueError(f"{text!r}: the radio relay takes udpin:HOST:PORT or udpout:HOST:PORT")
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setblocking(False)
    if scheme == "udpin":
        sock.bind((host, int(port_text)))
        return sock, None, True
    sock.bind(("127.0.0.1" if host in ("127.0.0.1", "localhost") else "0.0.0.0", 0))
    return sock, (host, int(port_text)), False
