"""Landmarks surveyed in geographic coordinates, projected once into the planner's frame.

A geographic points file gives each point's WGS84 latitude and longitude (degrees) and its
altitude above mean sea level (metres). The planner works in the local frame of
:class:`~gcs_planner.scenario.georef.LocalFrame` — the same azimuthal equidistant projection the
exporter inverts to write the mission — so a landmark goes in and comes back out of the same
formula, and a correction waypoint lands on its landmark.

The frame's origin is the scenario's (TOML ``[origin]`` or ``--origin``) when given; otherwise
the start point A at mean sea level, so that z is the altitude AMSL and the mission's altitudes
are the file's.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from gcs_planner.errors import InputError
from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.scenario.model import Origin

# (header line, [(line, {column: cell})], {column: label in messages}), as the format readers give
CellTable = tuple[int, list[tuple[int, dict[str, object]]], dict[str, str]]

_BOUNDS = {"lat": 90.0, "lon": 180.0, "alt": math.inf}


def is_geographic(labels: dict[str, str]) -> bool:
    """Whether a cell table holds lat/lon/alt rather than x/y/z."""
    return "lat" in labels


def _number(value: object) -> float | None:
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str) and value.strip():
        try:
            return float(value)
        except ValueError:
            return None
    return None


def _checked(path: Path, row: int, cells: dict[str, object], labels: dict[str, str]) -> list[float]:
    out = []
    for column in ("lat", "lon", "alt"):
        value = _number(cells[column])
        if value is None or not math.isfinite(value):
            what = "missing" if cells[column] in (None, "") else f"not a number: {cells[column]!r}"
            raise InputError(
                f"{what} ({'degrees' if column != 'alt' else 'metres above mean sea level'})",
                file=str(path),
                row=row,
                field=labels[column],
            )
        if abs(value) > _BOUNDS[column]:
            bound = _BOUNDS[column]
            raise InputError(
                f"must lie in [-{bound:g}, {bound:g}] degrees (got {value:g})",
                file=str(path),
                row=row,
                field=labels[column],
            )
        out.append(value)
    return out


def to_local(
    path: Path,
    table: CellTable,
    origin: Origin | None,
    is_start: Callable[[object], bool],
) -> tuple[CellTable, Origin]:
    """The table with x, y, z (metres, local frame) in place of lat, lon, alt, and the origin
    of that frame: ``origin``, else A's position at mean sea level (``is_start`` tells A's
    kind cell). Error messages keep naming the file's own columns."""
    header, rows, labels = table
    if not rows:
        raise InputError("no points after the header (header only)", file=str(path), row=header)
    geo = np.array([_checked(path, row, cells, labels) for row, cells in rows], dtype=float)
    if origin is None:
        start = next((i for i, (_, cells) in enumerate(rows) if is_start(cells["kind"])), 0)
        origin = Origin(float(geo[start, 0]), float(geo[start, 1]), 0.0)
    x, y, z = LocalFrame(origin).to_local(geo[:, 0], geo[:, 1], geo[:, 2])
    local_rows = []
    for i, (row, cells) in enumerate(rows):
        rest = {k: v for k, v in cells.items() if k not in ("lat", "lon", "alt")}
        local_rows.append((row, {**rest, "x": float(x[i]), "y": float(y[i]), "z": float(z[i])}))
    local_labels = {k: v for k, v in labels.items() if k not in ("lat", "lon", "alt")}
    local_labels.update(x=labels["lon"], y=labels["lat"], z=labels["alt"])
    return (header, local_rows, local_labels), origin
