"""A file read by MAVFTP in pieces by offset: what is held from the start, what is missing, and
the checks of a piece the vehicle sends before it is held."""

from __future__ import annotations

from gcs_planner.link.ftp_payload import DATA_MAX, FtpError, Packet


def contiguous(chunks: dict[int, bytes]) -> bytes:
    """The bytes held from offset 0 without a hole."""
    out = bytearray()
    while len(out) in chunks:
        out += chunks[len(out)]
    return bytes(out)


def gaps(chunks: dict[int, bytes], end: int | None, start: int) -> list[tuple[int, int]]:
    """Missing (offset, length) ranges from ``start``, in DATA_MAX pieces, to ``end`` (or to
    the highest byte read when the end is not known yet)."""
    covered = sorted((o, o + len(c)) for o, c in chunks.items())
    limit = end if end is not None else max((b for _, b in covered), default=0)
    missing: list[tuple[int, int]] = []
    pos = start
    for a, b in covered:
        if b <= pos:
            continue
        while pos < min(a, limit):
            missing.append((pos, min(DATA_MAX, min(a, limit) - pos)))
            pos += DATA_MAX
        pos = max(pos, b)
    while pos < limit:
        missing.append((pos, min(DATA_MAX, limit - pos)))
        pos += DATA_MAX
    return missing


def take(p: Packet, chunks: dict[int, bytes], end: int | None, path: str) -> None:
    """Hold the data of reply ``p`` in ``chunks``; a :class:`FtpError` when it lies past the
    file's end or differs from what was held for the same bytes."""
    if p.size == 0:
        return
    if end is not None and p.offset + p.size > end:
        raise FtpError(
            f"the vehicle sent bytes {p.offset}..{p.offset + p.size - 1} of {path}, past "
            f"its end at {end} bytes"
        )
    old = chunks.get(p.offset)
    if old is not None and old != p.data:
        raise FtpError(f"the vehicle sent two different contents for byte {p.offset} of {path}")
    for o, c in chunks.items():  # an overlap that is not the same piece is a lie
        if o != p.offset and o < p.offset + p.size and p.offset < o + len(c):
            lo, hi = max(o, p.offset), min(o + len(c), p.offset + p.size)
            if c[lo - o : hi - o] != p.data[lo - p.offset : hi - p.offset]:
                raise FtpError(f"the vehicle sent two different contents for byte {lo} of {path}")
            if o > p.offset:
                continue
            return  # already held
    chunks[p.offset] = p.data
