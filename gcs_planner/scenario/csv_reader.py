"""Layout of a points CSV: where the header and the cells are. Meaning is checked in readers.

The header names the columns ``id,x,y,z,kind,unreliable`` (metres in the local frame) or
``id,lat,lon,alt,kind,unreliable`` (WGS84 degrees, metres above mean sea level), in any order
(case and surrounding spaces ignored); ``lat`` in the header says which. Row numbers are the
file's line numbers, which is what a user's editor shows.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from gcs_planner.errors import InputError

COLUMNS = ("id", "x", "y", "z", "kind", "unreliable")
GEO_COLUMNS = ("id", "lat", "lon", "alt", "kind", "unreliable")

# (header line, [(line, {column: cell text})], {column: label used in error messages})
CellTable = tuple[int, list[tuple[int, dict[str, object]]], dict[str, str]]


def _decode(path: Path, data: bytes) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise InputError(
            f"not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
            "save the CSV as UTF-8",
            file=str(path),
            row=line,
        ) from None


def _header(path: Path, line: int, record: list[str]) -> tuple[dict[str, int], tuple[str, ...]]:
    names = [cell.strip().lower() for cell in record]
    columns = GEO_COLUMNS if "lat" in names or "lon" in names else COLUMNS
    where: dict[str, int] = {}
    for position, name in enumerate(names):
        if name in where:
            raise InputError(
                "column appears twice in the header", file=str(path), row=line, field=name
            )
        where[name] = position
    missing = [c for c in columns if c not in where]
    # Extra columns are refused rather than ignored: a misspelt column name must not pass
    # silently (a mistyped "unreliable" would otherwise drop every flag).
    extra = [n for n in names if n not in columns]
    if missing or extra:
        parts = []
        if missing:
            parts.append(f"missing column(s) {', '.join(missing)}")
        if extra:
            parts.append(f"unknown column(s) {', '.join(repr(e) for e in extra)}")
        raise InputError(
            f"bad header: {'; '.join(parts)} (expected {','.join(columns)})",
            file=str(path),
            row=line,
            field=(missing or extra)[0],
        )
    return where, columns


def read_csv_cells(path: Path) -> CellTable:
    """The header line, each non-blank record as its line number and cells by column, and the
    column labels (``lat``/``lon``/``alt`` present for a geographic file)."""
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", file=str(path)) from None
    text = _decode(path, data)
    if not text.strip():
        raise InputError("empty file: expected a header id,x,y,z,kind,unreliable", file=str(path))
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    header_line = 0
    where: dict[str, int] | None = None
    columns = COLUMNS
    rows: list[tuple[int, dict[str, object]]] = []
    try:
        for record in reader:
            line = reader.line_num
            if not any(cell.strip() for cell in record):
                continue
            if where is None:
                header_line, (where, columns) = line, _header(path, line, record)
                continue
            if len(record) != len(where):
                raise InputError(
                    f"expected {len(where)} fields, got {len(record)}", file=str(path), row=line
                )
            rows.append((line, {name: record[pos].strip() for name, pos in where.items()}))
    except csv.Error as exc:
        raise InputError(f"malformed CSV: {exc}", file=str(path), row=reader.line_num) from None
    if where is None:  # only separators and quotes, no header cell with text
        raise InputError("empty file: expected a header id,x,y,z,kind,unreliable", file=str(path))
    return header_line, rows, {name: name for name in columns}
