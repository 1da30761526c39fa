"""A MAVLink 2 connection over pymavlink: open, send, receive with a deadline, close.

Both ends of the mission protocol (this package's client and the mock vehicle in ``sim/``) talk
through a :class:`Link`, so that signing, the refusal of unsigned or wrongly signed peers and the
MAVLink 2 framing are set up in one place.
"""

from __future__ import annotations

import os
import threading
import time
from typing import Any

# pymavlink picks the wire protocol when mavutil is first imported; MAVLink 2 is needed for
# mission_type and for signing, so it is asked for before the import.
os.environ.setdefault("MAVLINK20", "1")

from pymavlink import mavutil  # noqa: E402

if getattr(mavutil.mavlink, "WIRE_PROTOCOL_VERSION", "1.0") != "2.0":
    # Someone imported mavutil before us without MAVLINK20: reload the dialect as MAVLink 2.
    os.environ["MAVLINK20"] = "1"
    mavutil.set_dialect("ardupilotmega")

from gcs_planner.errors import LinkError  # noqa: E402
from gcs_planner.link.signing import enable_signing  # noqa: E402

mavlink = mavutil.mavlink

# Component id a ground station uses (MAV_COMP_ID_MISSIONPLANNER).
GCS_COMPONENT = 190


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
        self.connection = connection
        try:
            self.conn = mavutil.mavlink_connection(
                connection,
                baud=baud,
                source_system=source_system,
                source_component=source_component,
                autoreconnect=False,
            )
        except (OSError, ValueError) as exc:
            raise LinkError(f"cannot open {connection!r}: {exc}") from exc
        self.mav = self.conn.mav
        self.signed = signing_key is not None
        if signing_key is not None:
            enable_signing(self.conn, signing_key)
        self.refused_signature = 0  # messages refused for a missing or wrong signature
        self.bad_data = 0
        self._send_lock = threading.Lock()

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
            msg = self.conn.recv_msg()
            if msg is not None:
                if msg.get_type() == "BAD_DATA":
                    if "signature" in str(getattr(msg, "reason", "")).lower():
                        self.refused_signature += 1
                    else:
                        self.bad_data += 1
                    continue
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
