"""MAVLink FTP's payload of FILE_TRANSFER_PROTOCOL: its opcodes and error codes, one packet
packed and unpacked, and the errors an FTP transfer ends with.

The payload (https://mavlink.io/en/services/ftp.html, "Payload"; ArduPilot's
``GCS_FTP::handle_file_transfer_protocol`` and ``send_reply`` in
libraries/GCS_MAVLink/GCS_FTP.cpp read and write the same layout): seq_number u16, session
u8, opcode u8, size u8, req_opcode u8, burst_complete u8, a padding byte, offset u32, then
239 data bytes, little-endian. A reply carries the request's sequence number plus one, its
opcode in req_opcode, and ACK (128) or NAK (129) with the error code in data[0].
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any

from gcs_planner.errors import LinkError

# Opcodes (the specification's table; GCS_FTP.h, enum FTP_OP).
NONE, TERMINATE_SESSION, RESET_SESSIONS, LIST_DIRECTORY, OPEN_FILE_RO, READ_FILE = range(6)
CREATE_FILE, WRITE_FILE, REMOVE_FILE = 6, 7, 8
OPEN_FILE_WO, CALC_FILE_CRC32, BURST_READ_FILE = 11, 14, 15
ACK, NAK = 128, 129
# NAK codes (data[0]).
ERRORS = {
    0: "no error",
    1: "failed",
    2: "failed with errno",
    3: "invalid data size",
    4: "invalid session",
    5: "no sessions available",
    6: "end of file",
    7: "unknown command",
    8: "file exists",
    9: "file protected",
    10: "file not found",
}
FAIL_ERRNO, EOF, UNKNOWN_COMMAND, FILE_NOT_FOUND = 2, 6, 7, 10
DATA_MAX = 239  # data bytes in one payload
PAYLOAD_LEN = 251
_HEAD = struct.Struct("<HBBBBBxI")


class FtpError(LinkError):
    """An FTP transfer failed: the vehicle refused it, went quiet, or sent what cannot be."""

    def __init__(self, message: str, code: int | None = None) -> None:
        super().__init__(message)
        self.code = code  # the NAK code when the vehicle refused


class FtpQuiet(FtpError):
    """The vehicle did not answer an FTP request through every resend (or a transfer made no
    progress for as long)."""


class FtpBusy(FtpError):
    """The vehicle kept refusing to open a file as in use (or had no session free), after
    each of our sessions was reset and a wait: someone else holds it."""


@dataclass(frozen=True)
class Packet:
    seq: int
    session: int
    opcode: int
    size: int
    req_opcode: int
    burst_complete: int
    offset: int
    data: bytes  # the first ``size`` data bytes

    def nak_text(self) -> str:
        code = self.data[0] if self.data else 0
        text = ERRORS.get(code, f"error code {code}")
        if code == FAIL_ERRNO and len(self.data) > 1:
            text += f" {self.data[1]}"
        return text


def pack(
    seq: int,
    session: int,
    opcode: int,
    offset: int = 0,
    data: bytes = b"",
    *,
    size: int | None = None,
    req_opcode: int = 0,
    burst_complete: int = 0,
) -> list[int]:
    """A FILE_TRANSFER_PROTOCOL payload (251 bytes) as pymavlink's encoder takes it."""
    if len(data) > DATA_MAX:
        raise ValueError(f"at most {DATA_MAX} data bytes, got {len(data)}")
    head = _HEAD.pack(seq & 0xFFFF, session & 0xFF, opcode, len(data) if size is None else size,
                      req_opcode, burst_complete, offset & 0xFFFFFFFF)  # fmt: skip
    return list(head + data + bytes(DATA_MAX - len(data)))


def unpack(payload: Any) -> Packet:
    """The header and data of a payload; a size past the 239 data bytes is a :class:`FtpError`."""
    raw = bytes(payload)
    if len(raw) < _HEAD.size:
        raw = raw + bytes(_HEAD.size - len(raw))
    seq, session, opcode, size, req, burst, offset = _HEAD.unpack_from(raw)
    if size > DATA_MAX:
        raise FtpError(
            f"the vehicle sent an FTP reply (opcode {opcode} to {req}) claiming {size} data "
            f"bytes: a payload carries at most {DATA_MAX}"
        )
    data = raw[_HEAD.size : _HEAD.size + size]
    return Packet(seq, session, opcode, size, req, burst, offset, data + bytes(size - len(data)))
