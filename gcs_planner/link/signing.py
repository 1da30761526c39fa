"""MAVLink 2 message signing: a passphrase becomes the 32-byte secret key, and incoming frames
are checked as the MAVLink specification ("Message signing") says.

With signing on, every incoming frame that is unsigned or signed with another key is refused, but
for the telemetry radio's own reports: a SiK radio (system 51) writes RADIO_STATUS to its host
unsigned, knowing no key, and both autopilots take it so (ArduPilot's ``accept_unsigned_callback``
in libraries/GCS_MAVLink/GCS_Signing.cpp accepts RADIO_STATUS and the older RADIO; PX4's
``MavlinkSignControl::accept_unsigned`` in src/modules/mavlink/mavlink_sign_control.cpp accepts
RADIO_STATUS whatever the signing mode), so the pacing that reads them
(:mod:`gcs_planner.link.pacing`) runs on a signed link too. Like the autopilots, the sender's ids
are not asked: pymavlink's callback is given the message id only, and a forged report can only
slow a transfer down. The check itself is ours, not pymavlink's: pymavlink stores a
stream's timestamp *before* it has verified the signature, so one wrong-key frame stamped far in
the future makes every later frame of the rightful peer "too old" and locks it out until restart.
Here a frame advances its stream's timestamp (and our own sending clock) only after its signature
verified.
"""

from __future__ import annotations

import hashlib
import hmac
import struct
from functools import partial
from typing import Any

# A new stream may start at most one minute behind our clock (the specification's 6,000,000
# units of 10 microseconds), so an old recording cannot open a stream.
NEW_STREAM_WINDOW = 6_000_000
_STAMP = struct.Struct("<IH")
# Messages taken unsigned on a signed link: RADIO_STATUS (109) and RADIO (166, ardupilotmega.xml),
# ArduPilot's accept list.
UNSIGNED_ACCEPTED = frozenset({109, 166})


def accept_unsigned(mav: Any, msg_id: int) -> bool:
    """pymavlink's ``allow_unsigned_callback``: only the radio's reports pass unsigned."""
    del mav
    return msg_id in UNSIGNED_ACCEPTED


def key_from_passphrase(passphrase: str) -> bytes:
    """The 32-byte signing key of ``passphrase`` (SHA-256 of its UTF-8 bytes, as QGC does)."""
    if not passphrase:
        raise ValueError("an empty signing passphrase gives no protection")
    return hashlib.sha256(passphrase.encode("utf-8")).digest()


def signature_of(key: bytes, frame_without_signature: bytes) -> bytes:
    """The 48-bit signature: the first 6 bytes of SHA-256(key + header + payload + CRC + link id +
    timestamp)."""
    return hashlib.sha256(key + frame_without_signature).digest()[:6]


def check_signature(mav: Any, msgbuf: bytes, src_system: int, src_component: int) -> bool:
    """True when the signed frame ``msgbuf`` verifies and is newer than its stream's last frame.

    Order matters: signature first, then the timestamp; only a verified frame moves its stream's
    timestamp and our sending clock forward.
    """
    signing = mav.signing
    key = signing.secret_key
    if key is None or len(msgbuf) < 13:
        return False
    buf = bytes(msgbuf)
    if not hmac.compare_digest(signature_of(key, buf[:-6]), buf[-6:]):
        return False
    low, high = _STAMP.unpack(buf[-12:-6])
    timestamp = low + (high << 32)
    stream = (buf[-13], src_system, src_component)
    last = signing.stream_timestamps.get(stream)
    if last is not None:
        if timestamp <= last:
            return False  # a replay, or frames of the stream out of order
    elif timestamp + NEW_STREAM_WINDOW < signing.timestamp:
        return False  # a new stream that starts too far in the past
    signing.stream_timestamps[stream] = timestamp
    signing.timestamp = max(signing.timestamp, timestamp)
    return True


def enable_signing(conn: Any, key: bytes) -> None:
    """Sign every outgoing frame of the pymavlink connection ``conn``, refuse unsigned ones (but
    the radio's reports, :func:`accept_unsigned`) and check incoming signatures with
    :func:`check_signature`."""
    if len(key) != 32:
        raise ValueError("a MAVLink 2 signing key is 32 bytes")
    conn.setup_signing(key, sign_outgoing=True, allow_unsigned_callback=accept_unsigned)
    # pymavlink looks the check up on the MAVLink object at each frame: ours replaces its own for
    # this connection only.
    conn.mav.check_signature = partial(check_signature, conn.mav)
