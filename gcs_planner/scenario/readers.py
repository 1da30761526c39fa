"""Reading a scenario from the user's files: the one entry point :func:`load_scenario`.

The format modules (:mod:`.xlsx`, :mod:`.csv_reader`, :mod:`.geojson_reader`,
:mod:`.toml_reader`) know where things are in a file; :mod:`.geographic` projects landmarks given
in latitude, longitude and altitude into the local frame; this module knows what the cells mean
and checks them, once for every format, so that a workbook and a CSV with the same points are
judged by the same rules and the same messages.
"""

from __future__ import annotations

import math
import os
import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from gcs_planner.aircraft.profile import (
    DEFAULT_CRUISE_AIRSPEED,
    DEFAULT_LEG_MODEL,
    DEFAULT_RESERVE_M,
    DEFAULT_RESERVE_MAX_SHARE,
    LEG_MODELS,
    MAX_BANK_DEG,
    turn_radius_from,
)
from gcs_planner.errors import InputError
from gcs_planner.scenario import csv_reader, geographic, toml_reader
from gcs_planner.scenario.model import PARAMETER_NAMES, Kind, Origin, Parameters, Scenario

COMMAND_LINE = "command line"
PARAMETER_KEYS = tuple(f.name for f in fields(Parameters))
# The aircraft beyond the planning parameters ([vehicle] in a TOML, flags on the command line).
VEHICLE_EXTRA_KEYS = ("cruise_airspeed", "max_bank_angle", "leg_model")
OVERRIDE_KEYS = (*PARAMETER_KEYS, *VEHICLE_EXTRA_KEYS, "heading_at_a", "origin")

# Kind vocabulary shared by both point formats: the planner's letters, and the contest's codes
# (1 = V, 0 = H, "A点", "B点") so that a workbook exported to CSV still reads.
_KIND_WORDS = {
    "A": Kind.A, "A点": Kind.A,
    "B": Kind.B, "B点": Kind.B,
    "V": Kind.V, "1": Kind.V,
    "H": Kind.H, "0": Kind.H,
}  # fmt: skip
_FLAG_WORDS = {"0": False, "1": True, "FALSE": False, "TRUE": True}


@dataclass(frozen=True)
class Points:
    """The checked point table of one file, in the file's order."""

    ids: tuple[str, ...]
    xyz: np.ndarray
    kind: np.ndarray
    unreliable: np.ndarray
    # The frame a geographic file was projected into (None for a file in local metres).
    origin: Origin | None = None


# Files of points only (no parameters), by suffix.
POINTS_SUFFIXES = (".csv", ".xlsx", ".geojson", ".json")


def load_scenario(
    path: str | os.PathLike[str], overrides: Mapping[str, object] | None = None
) -> Scenario:
    """Read a scenario from a contest workbook (.xlsx), a points CSV (.csv: local x, y, z or
    geographic lat, lon, alt), GeoJSON points (.geojson) or a scenario TOML.

    ``overrides`` are values from command-line flags (parameter names, ``heading_at_a`` as three
    numbers, ``origin`` as an :class:`Origin`); ``None`` values are ignored and the others win
    over the scenario file. A bare workbook or CSV has no parameters of its own, so the six
    required ones must then all be given as overrides. Raises :class:`InputError` naming the
    file, row and field of anything wrong.
    """
    path = Path(path)
    given = {k: v for k, v in (overrides or {}).items() if v is not None}
    unknown = sorted(set(given) - set(OVERRIDE_KEYS))
    if unknown:  # a caller's bug, not the user's
        raise ValueError(f"unknown override(s): {', '.join(unknown)}")
    _check_is_file(path)
    suffix = path.suffix.lower()
    vehicle: dict[str, object] = {}
    # The origin is known before the points are read: a geographic file is projected with it.
    given_origin = _override_origin(given["origin"]) if "origin" in given else None
    if suffix == ".toml":
        spec = toml_reader.read_scenario_toml(path)
        points = load_points(spec.points, given_origin or spec.origin)
        values = dict(spec.parameters)
        sources = {k: (str(path), spec.parameter_lines.get(k)) for k in values}
        for key, value in spec.vehicle.items():
            sources[key] = (str(path), spec.vehicle_lines.get(key))
            if key in PARAMETER_KEYS:
                values[key] = value  # type: ignore[assignment]
            else:
                vehicle[key] = value
        name = spec.name or path.stem
        origin, heading = spec.origin, spec.heading_at_a
    elif suffix in POINTS_SUFFIXES:
        points = load_points(path, given_origin)
        values, sources = {}, {}
        name, origin, heading = path.stem, None, None
    else:
        raise InputError(
            f"unknown file type {path.suffix!r}: expected .xlsx, .csv, .geojson or .toml",
            file=str(path),
        )
    if origin is None:
        origin = points.origin  # a geographic file's frame, when nobody gave one

    for key in PARAMETER_KEYS:
        if key in given:
            values[key] = _override_number(key, given[key])
            sources[key] = (COMMAND_LINE, None)
    for key in VEHICLE_EXTRA_KEYS:
        if key in given:
            vehicle[key] = given[key] if key == "leg_model" else _override_number(key, given[key])
            sources[key] = (COMMAND_LINE, None)
    # On the command line a radius wins over a bank from the file, and a bank over a radius.
    if "turn_radius" in given and "max_bank_angle" not in given:
        vehicle.pop("max_bank_angle", None)
    elif "max_bank_angle" in given and "turn_radius" not in given:
        values.pop("turn_radius", None)
    extra = _vehicle(path, vehicle, values, sources)
    if given_origin is not None:
        origin = given_origin
    if "heading_at_a" in given:
        heading = toml_reader.check_heading(
            _as_list(given["heading_at_a"]), file=COMMAND_LINE, row=None
        )
    if "reserve" in values:
        extra["reserve_source"] = "stated"
    elif _default_reserve(values, extra):
        extra["reserve_source"] = "default"
    params = _parameters(path, suffix, values, sources)
    return Scenario(
        ids=points.ids,
        xyz=points.xyz,
        kind=points.kind,
        unreliable=points.unreliable,
        params=params,
        name=name,
        source=str(path),
        origin=origin,
        heading_at_a=heading,
        **extra,
    )


def load_points(path: str | os.PathLike[str], origin: Origin | None = None) -> Points:
    """The checked points of a .csv, .xlsx or .geojson file. Geographic points (lat, lon, alt)
    are projected into the local frame of ``origin``, or of A at mean sea level when None
    (``Points.origin`` says which)."""
    path = Path(path)
    _check_is_file(path)
    suffix = path.suffix.lower()
    if suffix == ".csv":
        table = csv_reader.read_csv_cells(path)
    elif suffix == ".xlsx":
        from gcs_planner.scenario import xlsx  # openpyxl: only for workbooks

        table = xlsx.read_workbook_cells(path)
    elif suffix in (".geojson", ".json"):
        from gcs_planner.scenario.geojson_reader import read_geojson_cells

        table = read_geojson_cells(path)
    else:
        raise InputError(
            f"unknown points file type {path.suffix!r}: expected .csv, .xlsx or .geojson",
            file=str(path),
        )
    frame = None
    if geographic.is_geographic(table[2]):
        table, frame = geographic.to_local(path, table, origin, lambda cell: _kind(cell) == Kind.A)
    found = _points(path, *table)
    return Points(found.ids, found.xyz, found.kind, found.unreliable, frame)


def _check_is_file(path: Path) -> None:
    try:
        if path.is_dir():
            raise InputError("is a directory, not a scenario file", file=str(path))
        if not path.is_file():
            raise InputError("no such file", file=str(path))
    except OSError as exc:  # e.g. a name too long for the file system
        raise InputError(f"cannot open: {exc.strerror or exc}", file=str(path)) from None
    if not os.access(path, os.R_OK):
        raise InputError("file is not readable (permission denied)", file=str(path))


# --- parameters ---------------------------------------------------------------------------


def _as_list(value: object) -> object:
    """A heading override as a list of floats where it can be one; check_heading judges it."""
    if not isinstance(value, (tuple, list, np.ndarray)):
        return value
    try:
        return [float(c) for c in value]
    except (TypeError, ValueError):
        return list(value)


def _override_number(key: str, value: object) -> float:
    if isinstance(value, bool):
        raise InputError(f"must be a number (got {value!r})", file=COMMAND_LINE, field=key)
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(
            f"must be a number (got {value!r})", file=COMMAND_LINE, field=key
        ) from None


def _override_origin(value: object) -> Origin:
    if not isinstance(value, Origin):
        raise ValueError(f"override 'origin' must be an Origin, got {type(value).__name__}")
    return toml_reader.check_origin(value.lat, value.lon, value.alt, file=COMMAND_LINE)


def _default_reserve(values: dict[str, float], extra: dict[str, object]) -> bool:
    """A scenario flown on airplane legs keeps a flight reserve unless one is given: a plan
    that uses its limits to the metre is lost by the first late turn (vehicle.DEFAULT_RESERVE_M;
    with an envelope derived from the autopilot's terms, the reserve is derived too:
    cli/vehicle_from.py). Straight and cs3d legs reproduce the contest's model and plan without
    one. True when it filled one in."""
    if "reserve" in values or any(k not in values for k in PARAMETER_NAMES):
        return False
    radius = values.get("turn_radius", Parameters.turn_radius)
    if extra.get("leg_model", DEFAULT_LEG_MODEL) != "airplane" or not radius > 0:
        return False
    try:
        tightest = min(float(values[k]) for k in PARAMETER_NAMES[:5]) / float(values["delta"])
    except (TypeError, ValueError, ZeroDivisionError):
        return False  # _parameters says what is wrong with them
    if math.isfinite(tightest) and tightest > 0:
        values["reserve"] = min(DEFAULT_RESERVE_M, DEFAULT_RESERVE_MAX_SHARE * tightest)
        return True
    return False


def _parameters(
    path: Path, suffix: str, values: dict[str, float], sources: dict[str, tuple[str, int | None]]
) -> Parameters:
    missing = [k for k in PARAMETER_NAMES if k not in values]
    if missing:
        flags = " ".join(f"--{k} VALUE" for k in missing)
        where = (
            "in the [parameters] table of the TOML"
            if suffix == ".toml"
            else "in a scenario TOML's [parameters] table"
        )
        raise InputError(
            f"missing parameter(s) {', '.join(missing)}: give them as flags ({flags}) or {where}",
            file=str(path),
            field=missing[0],
        )
    params = Parameters(**values)
    problems = params.validate()
    if problems:
        # validate() starts each message with the parameter's name: blame where it came from.
        first = problems[0].split()[0]
        file, row = sources.get(first, (str(path), None))
        raise InputError("; ".join(problems), file=file, row=row, field=first)
    return params


def _vehicle(
    path: Path,
    vehicle: dict[str, object],
    values: dict[str, float],
    sources: dict[str, tuple[str, int | None]],
) -> dict[str, object]:
    """The Scenario fields of the aircraft (leg model, airspeed, radius source); fills the
    turning radius into ``values`` when it comes from airspeed and bank."""

    def fail(key: str, message: str) -> InputError:
        file, row = sources.get(key, (str(path), None))
        return InputError(message, file=file, row=row, field=key)

    out: dict[str, object] = {}
    leg_model = vehicle.get("leg_model")
    if leg_model is not None:
        if leg_model not in LEG_MODELS:
            raise fail(
                "leg_model", f"unknown leg model {leg_model!r}: one of {', '.join(LEG_MODELS)}"
            )
        out["leg_model"] = leg_model
    airspeed = vehicle.get("cruise_airspeed")
    if airspeed is not None:
        if not (math.isfinite(airspeed) and 0 < airspeed <= 300):  # type: ignore[operator]
            raise fail("cruise_airspeed", f"must lie in (0, 300] m/s (got {airspeed!r})")
        out["cruise_airspeed"] = float(airspeed)  # type: ignore[arg-type]
    bank = vehicle.get("max_bank_angle")
    if bank is not None:
        if not (math.isfinite(bank) and 0 < bank <= MAX_BANK_DEG):  # type: ignore[operator]
            raise fail(
                "max_bank_angle", f"must lie in (0, {MAX_BANK_DEG:g}] degrees (got {bank!r})"
            )
        if "turn_radius" in values:
            raise fail(
                "max_bank_angle",
                "give either turn_radius or cruise_airspeed with max_bank_angle, not both",
            )
        speed = float(airspeed) if airspeed is not None else DEFAULT_CRUISE_AIRSPEED  # type: ignore[arg-type]
        values["turn_radius"] = turn_radius_from(speed, float(bank))  # type: ignore[arg-type]
        out["radius_source"] = "airspeed and bank"
    return out


# --- points -------------------------------------------------------------------------------


def _points(
    path: Path,
    header_row: int,
    rows: list[tuple[int, dict[str, object]]],
    labels: dict[str, str],
) -> Points:
    file = str(path)
    if not rows:
        raise InputError("no points after the header (header only)", file=file, row=header_row)
    ids: list[str] = []
    xyz = np.empty((len(rows), 3), dtype=np.float64)
    kind = np.empty(len(rows), dtype=np.uint8)
    unreliable = np.empty(len(rows), dtype=bool)
    first_row: dict[str, int] = {}
    ends: dict[Kind, list[int]] = {Kind.A: [], Kind.B: []}
    for i, (row, cells) in enumerate(rows):

        def fail(message: str, column: str, row: int = row) -> InputError:
            return InputError(message, file=file, row=row, field=labels[column])

        point_id = _point_id(cells["id"])
        if not point_id:
            raise fail("missing point id", "id")
        if point_id in first_row:
            raise fail(f"duplicate id {point_id!r} (first at row {first_row[point_id]})", "id")
        first_row[point_id] = row
        ids.append(point_id)
        for axis, column in enumerate(("x", "y", "z")):
            value, why = _coordinate(cells[column], MAX_COORDINATE[axis])
            if why:
                raise fail(why, column)
            xyz[i, axis] = value
        point_kind = _kind(cells["kind"])
        if point_kind is None:
            raise fail(
                f"unknown kind {_show(cells['kind'])}: expected A, B, V or H "
                "(or the contest's 1 = V, 0 = H, A点, B点)",
                "kind",
            )
        kind[i] = point_kind
        flag = _flag(cells["unreliable"])
        if flag is None:
            raise fail(
                f"must be 0 or 1 (or true/false), got {_show(cells['unreliable'])}", "unreliable"
            )
        if flag and point_kind in ends:
            # A and B make no correction, so a flag there is a mistake in the file (often a
            # shifted row), not something to model.
            raise fail(
                f"the {point_kind.name} point cannot be flagged unreliable (it makes no "
                "correction)",
                "unreliable",
            )
        unreliable[i] = flag
        if point_kind in ends:
            ends[point_kind].append(row)
    for end, word in ((Kind.A, "start"), (Kind.B, "end")):
        if not ends[end]:
            raise InputError(
                f"no {word} point: one row must have kind {end.name}",
                file=file,
                row=header_row,
                field=labels["kind"],
            )
        if len(ends[end]) > 1:
            raise InputError(
                f"more than one {word} point {end.name} (rows "
                f"{', '.join(map(str, ends[end]))}); exactly one is allowed",
                file=file, row=ends[end][1], field=labels["kind"],
            )  # fmt: skip
    _check_ends_apart(file, rows, xyz, kind, labels)
    return Points(tuple(ids), xyz, kind, unreliable)


# A and B closer than this (3D, metres) are one place: a mission of no length, nothing to plan.
SAME_POINT_M = 1e-6


def _check_ends_apart(
    file: str,
    rows: list[tuple[int, dict[str, object]]],
    xyz: np.ndarray,
    kind: np.ndarray,
    labels: dict[str, str],
) -> None:
    """Refuse a scenario whose A and B are the same point (a 0 m mission, usually B's row
    copied from A's): the planner would "plan" it and write a mission that goes nowhere."""
    a = int(np.flatnonzero(kind == Kind.A)[0])
    b = int(np.flatnonzero(kind == Kind.B)[0])
    if float(np.linalg.norm(xyz[b] - xyz[a])) >= SAME_POINT_M:
        return
    x, y, z = (f"{float(c):g}" for c in xyz[a])
    raise InputError(
        f"A and B are the same point: rows {rows[a][0]} and {rows[b][0]} are both at local "
        f"x={x} m, y={y} m, z={z} m (a 0 m mission); B must be where the mission ends",
        file=file,
        row=rows[b][0],
        field=labels["kind"],
    )


def _show(value: object) -> str:
    return "an empty cell" if value is None or value == "" else repr(value)


def _point_id(value: object) -> str:
    if value is None:
        return ""
    if isinstance(value, float) and value.is_integer():
        return str(int(value))  # a spreadsheet stores 12 as 12.0; the user wrote "12"
    return str(value).strip()


# Largest magnitude of a coordinate, metres (x east, y north, z up; for a geographic file the
# same cells hold degrees, checked again by their own ranges). Beyond these a number is a typo
# or a unit mix-up, not a place: no point on Earth is farther than half its circumference
# (20,004 km) from the origin, and 100 km up is space. A 1e300 would otherwise reach the
# search's distance tables and fail there ("p too large") with no row named.
MAX_COORDINATE = (2.0e7, 2.0e7, 1.0e5)


def _coordinate(value: object, limit: float = math.inf) -> tuple[float, str]:
    """The coordinate in metres, and why it is invalid ("" when valid)."""
    if isinstance(value, bool):
        return 0.0, f"not a number: {value!r}"
    if isinstance(value, (int, float)):
        number = float(value)
    elif isinstance(value, str):
        if not value.strip():
            return 0.0, "missing coordinate (empty cell)"
        try:
            number = float(value)
        except ValueError:
            return 0.0, f"not a number: {value!r}"
    elif value is None:
        return 0.0, "missing coordinate (empty cell)"
    else:
        return 0.0, f"not a number: {value!r}"
    if not math.isfinite(number):
        return 0.0, f"coordinate must be finite (got {value!r})"
    if abs(number) > limit:
        return 0.0, f"coordinate {number:g} m is out of range (at most {limit:,.0f} m either way)"
    return number, ""


def _word(value: object) -> str | None:
    """A cell as an upper-case token; integral numbers as their integer text."""
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, (int, float)):
        if not math.isfinite(value) or not float(value).is_integer():
            return None
        return str(int(value))
    if isinstance(value, str):
        return unicodedata.normalize("NFKC", value).strip().upper()
    return None


def _kind(value: object) -> Kind | None:
    return _KIND_WORDS.get(_word(value) or "")


def _flag(value: object) -> bool | None:
    if isinstance(value, bool):
        return value
    word = _word(value)
    if word in ("0.0", "1.0"):
        word = word[0]
    return _FLAG_WORDS.get(word or "")
