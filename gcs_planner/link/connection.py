"""A MAVLink 2 connection over pymavlink: open, send, receive with a deadline, close.

Both ends of the mission protocol (this package's client and the mock vehicle in ``sim/``) talk
through a :class:`Link`, so that signing, the refusal of unsigned or wrongly signed peers and the
MAVLink 2 framing are set up in one place.
"""

from __future__ import annotations

import errno
import os
import re
import socket
import stat
import threading
import time
from collections.abc import Callable
from typing import Any

# pymavlink picks the wire protocol when mavutil is first imported; MAVLink 2 is needed for
# mission_type and for signing, so it is asked for before the import.
os.environ.setdefault("MAVLINK20", "1")

from pymavlink import mavutil  # noqa: E402

if getattr(mavutil.mavlink, "WIRE_PROTOCOL_VERSION", "1.0") != "2.0":
    # Someone imported mavutil before us without MAVLINK20: reload the dialect as MAVLink 2.
    os.environ["MAVLINK20"] = "1"
    mavutil.set_dialect("ardupilotmega")

from gcs_planner.errors import InputError, LinkError  # noqa: E402
from gcs_planner.link.signing import enable_signing  # noqa: E402

mavlink = mavutil.mavlink

# Component id a ground station uses (MAV_COMP_ID_MISSIONPLANNER).
GCS_COMPONENT = 190

# The network forms pymavlink opens; anything else must be a serial device.
NETWORK_SCHEMES = ("udpin", "udpout", "udp", "udpbcast", "tcp", "tcpin")
_LISTENING = {"udpin": socket.SOCK_DGRAM, "udp": socket.SOCK_DGRAM, "tcpin": socket.SOCK_STREAM}
CONNECTION_FORMS = (
    "udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT or a serial device such "
    "as /dev/ttyUSB0 or COM3"
)


def check_connection(connection: str) -> str:
    """``connection`` if it is a form pymavlink opens as we mean it, else :class:`InputError`.

    pymavlink itself takes any ``a:b`` as UDP and anything else as a serial port or a log file,
    so a typo surfaces later as an unrelated failure; here it is named as what it is.
    """
    flag = "--connect"
    text = connection.strip()
    scheme, sep, rest = text.partition(":")
    if sep and scheme.lower() in NETWORK_SCHEMES:
        host, sep2, port_text = rest.rpartition(":")
        if not sep2 or not host or not port_text.isdigit():
            raise InputError(f"{connection!r} is not {scheme}:HOST:PORT", field=flag)
        port = int(port_text)
        if not 1 <= port <= 65535:
            raise InputError(f"port {port_text} of {connection!r} is not in 1..65535", field=flag)
        return text
    if re.fullmatch(r"(?i)com\d+", text) or text.startswith("/dev/"):
        return text
    try:
        if stat.S_ISCHR(os.stat(text).st_mode):
            return text  # a serial device under another name (a pty, a udev symlink)
    except OSError:
        pass
    raise InputError(f"{connection!r} is not a connection: expected {CONNECTION_FORMS}", field=flag)


def _check_port_free(connection: str) -> None:
    """Refuse a listening connection on a port another process holds.

    pymavlink binds with SO_REUSEADDR, which on Linux lets a second listener bind the same UDP
    port and silently share (or steal) its traffic; a bind without it fails as it should.
    """
    scheme, _, rest = connection.partition(":")
    kind = _LISTENING.get(scheme.lower())
    if kind is None:
        return
    host, _, port = rest.rpartition(":")
    with socket.socket(socket.AF_INET, kind) as probe:
        try:
            probe.bind((host, int(port)))
        except OSError as exc:
            reason = exc.strerror or str(exc)
            raise InputError(
                f"cannot listen on {host}:{port} ({reason}): is another vehicle or ground "
                "station already using it?",
                field="--connect",
            ) from None


class Link:
    """One MAVLink connection (``udpin:``, ``udpout:``, ``tcp:``, ``tcpin:``, a serial device).

    ``send`` may be called from several threads; ``recv`` from one thread only.
    """

    def __init__(
        self,
        connection: str,
        *,
        baud: int = 57600,
        source_system: int = 255,
        source_component: int = GCS_COMPONENT,
        signing_key: bytes | None = None,
    ) -> None:
        connection = check_connection(connection)
        for name, value, low in (
            ("source system", source_system, 1),
            ("source component", source_component, 0),
        ):
            if not low <= value <= 255:
                raise InputError(f"{name} {value} is not in {low}..255")
        self.connection = connection
        _check_port_free(connection)
        self.conn = _open(connection, baud, source_system, source_component)
        self.mav = self.conn.mav
        # The UDP address the last datagram came from (udpin only; None otherwise): a vehicle
        # binds a transfer to it, since two ground stations may use the same ids.
        self.last_sender: Any = None
        if isinstance(self.conn, mavutil.mavudp):
            self.conn.recv = self._udp_recv
        self.signed = signing_key is not None
        if signing_key is not None:
            enable_signing(self.conn, signing_key)
        self.refused_signature = 0  # messages refused for a missing or wrong signature
        self.peer_signed = 0  # signed frames heard while we do not sign: the peer wants a key
        self.bad_data = 0
        # Datagrams the other end's host refused (ICMP port unreachable on udpout): nothing
        # listens there, which the heartbeat wait can say instead of only "no heartbeat".
        self.refused_datagrams = 0
        self.peer_closed = False  # a TCP peer reset or closed the connection
        if isinstance(self.conn, mavutil.mavtcp):
            # pymavlink prints these on stdout; ours is a flag the client's errors name.
            self.conn.handle_disconnect = self._on_peer_closed
            self.conn.handle_eof = self._on_peer_closed
        self._send_lock = threading.Lock()
        # Called with every message ``recv`` returns, whoever reads: what a session keeps
        # track of (the vehicle's AUTOPILOT_VERSION) is seen by a parameter read too.
        self.watchers: list[Callable[[Any], None]] = []

    def _on_peer_closed(self) -> None:
        self.peer_closed = True

    def _udp_recv(self, n: int | None = None) -> bytes:
        """pymavlink's mavudp.recv, keeping the sender's address, and knowing that MAVLink frames
        never span UDP datagrams: a truncated frame left by the previous datagram is dropped
        instead of swallowing the frames of this one (pymavlink parses UDP as a byte stream)."""
        conn = self.conn
        try:
            data, sender = conn.port.recvfrom(65535)
        except OSError as exc:
            if exc.errno == errno.ECONNREFUSED:
                self.refused_datagrams += 1
                return b""
            if exc.errno in (errno.EAGAIN, errno.EWOULDBLOCK):
                return b""
            raise
        if conn.udp_server:
            if hasattr(conn, "clients"):  # answers go to every client heard (pymavlink >= 2.4.41)
                conn.clients.add(sender)
                conn.clients_last_alive[sender] = time.time()
            else:
                conn.last_address = sender
        elif getattr(conn, "broadcast", False):
            conn.last_address = sender
        self.last_sender = sender
        if _partial_frame_pending(conn.mav):
            conn.mav.buf = bytearray()
            conn.mav.buf_index = 0
            conn.mav.expected_length = mavlink.HEADER_LEN_V1 + 2
            self.bad_data += 1
        return data

    # The sending side -------------------------------------------------------------------------
    def send(self, msg: Any) -> None:
        with self._send_lock:
            self.mav.send(msg)

    def write_raw(self, buf: bytes) -> None:
        """Write an already packed frame (used by fault injection to release held frames)."""
        with self._send_lock:
            self.conn.write(buf)

    # The receiving side -----------------------------------------------------------------------
    def recv(self, timeout: float) -> Any | None:
        """The next valid message within ``timeout`` seconds, else None.

        Frames that fail their signature check (unsigned while we sign, or another key) are
        counted in ``refused_signature`` and never returned.
        """
        deadline = time.monotonic() + max(0.0, timeout)
        while True:
            try:
                msg = self.conn.recv_msg()
            except Exception:  # a hostile frame must not end the link
                # pymavlink's robust parser turns most bad frames into BAD_DATA; what slips
                # through (a field it cannot unpack) is counted the same way.
                self.bad_data += 1
                msg = None
                if time.monotonic() >= deadline:
                    return None
            if msg is not None:
                if msg.get_type() == "BAD_DATA":
                    if "signature" in str(getattr(msg, "reason", "")).lower():
                        self.refused_signature += 1
                    else:
                        self.bad_data += 1
                    continue
                if not self.signed and _is_signed(msg):
                    self.peer_signed += 1
                for watch in self.watchers:
                    watch(msg)
                return msg
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            self.conn.select(min(remaining, 0.05))

    def close(self) -> None:
        try:
            self.conn.close()
        except OSError:
            pass

    def __enter__(self) -> Link:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# A TCP peer that refuses may be starting: this many attempts, a second apart, before giving up.
TCP_ATTEMPTS = 3


def _open(connection: str, baud: int, source_system: int, source_component: int) -> Any:
    """pymavlink's connection, with its "Connection refused sleeping" retries replaced by
    ours: pymavlink prints each on stdout (mavutil.mavtcp.do_connect), which mixes with what a
    command prints there, and ends with a bare exception."""
    is_tcp = connection.lower().startswith("tcp:")
    attempts = TCP_ATTEMPTS if is_tcp else 1
    for attempt in range(attempts):
        try:
            return mavutil.mavlink_connection(
                connection,
                baud=baud,
                source_system=source_system,
                source_component=source_component,
                autoreconnect=False,
                retries=0,  # one attempt per call: pymavlink prints before each retry
            )
        except ConnectionRefusedError:
            if attempt + 1 < attempts:
                time.sleep(1.0)
                continue
            raise LinkError(
                f"{connection} refused the connection ({attempts} attempts, 1 s apart): is "
                "the vehicle or its MAVLink router listening there?"
            ) from None
        except (OSError, ValueError) as exc:
            reason = getattr(exc, "strerror", None) or str(exc)
            if is_tcp and isinstance(exc, OSError):
                raise LinkError(f"cannot connect to {connection}: {reason}") from None
            raise InputError(f"cannot open {connection!r}: {reason}", field="--connect") from None
    raise AssertionError("unreachable")


def _partial_frame_pending(mav: Any) -> bool:
    """True when pymavlink's parse buffer holds the start of a frame and not all of it."""
    n = mav.buf_len()
    if n == 0:
        return False
    buf, i = mav.buf, mav.buf_index
    if buf[i] == 0xFD:  # MAVLink 2: 10-byte header, 2-byte CRC, 13-byte signature if flagged
        if n < 3:
            return True
        need = buf[i + 1] + 12 + (13 if buf[i + 2] & 0x01 else 0)
    elif buf[i] == 0xFE:  # MAVLink 1: 6-byte header, 2-byte CRC
        if n < 2:
            return True
        need = buf[i + 1] + 8
    else:
        return False  # garbage: the parser skips it as a bad prefix
    return n < need


def _is_signed(msg: Any) -> bool:
    buf = msg.get_msgbuf()
    return bool(buf) and len(buf) > 2 and buf[0] == 0xFD and bool(buf[2] & 0x01)


def open_link(
    connection: str,
    *,
    baud: int = 57600,
    signing_key: bytes | None = None,
    source_system: int = 255,
    source_component: int = GCS_COMPONENT,
) -> Link:
    """Open ``connection`` as a ground station (system 255, component 190 by default)."""
    return Link(
        connection,
        baud=baud,
        source_system=source_system,
        source_component=source_component,
        signing_key=signing_key,
    )
