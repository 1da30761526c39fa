"""MAVLink 2 message signing: a passphrase becomes the 32-byte secret key.

With signing on, pymavlink refuses every incoming frame that is unsigned or signed with another
key (no ``allow_unsigned_callback``), which is what "an unsigned or wrong-key peer is refused"
asks for.
"""

from __future__ import annotations

import hashlib
from typing import Any


def key_from_passphrase(passphrase: str) -> bytes:
    """The 32-byte signing key of ``passphrase`` (SHA-256 of its UTF-8 bytes, as QGC does)."""
    if not passphrase:
        raise ValueError("an empty signing passphrase gives no protection")
    return hashlib.sha256(passphrase.encode("utf-8")).digest()


def enable_signing(conn: Any, key: bytes) -> None:
    """Sign every outgoing frame of the pymavlink connection ``conn`` and refuse unsigned ones."""
    if len(key) != 32:
        raise ValueError("a MAVLink 2 signing key is 32 bytes")
    conn.setup_signing(key, sign_outgoing=True, allow_unsigned_callback=None)
