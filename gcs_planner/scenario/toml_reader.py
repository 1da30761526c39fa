"""The scenario TOML: which points file, the parameters, the origin and the initial heading.

Every key is checked against the known ones, so that a typo (``alpah1``) is an error and not a
silently ignored value. tomllib gives no line numbers for keys; errors find them in the text,
best effort, because a user fixes a file faster when told which line.
"""

from __future__ import annotations

import math
import re
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path

from gcs_planner.aircraft.autopilot import AUTOPILOTS
from gcs_planner.errors import InputError
from gcs_planner.scenario.model import Origin, Parameters
from gcs_planner.sim.turbulence import parse_turbulence

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised only on Python 3.10
    import tomli as tomllib

PARAMETER_KEYS = tuple(f.name for f in fields(Parameters))
TOP_KEYS = (
    "name",
    "points",
    "heading_at_a",
    "parameters",
    "origin",
    "vehicle",
    "environment",
    # The dry run's seldom-changed settings (gcs_planner/dryrun/settings.py reads and checks
    # them); a scenario is read the same with or without them.
    "dry_run",
)
# [vehicle] in the autopilot's terms: the envelope is derived from these (cli/vehicle_from.py,
# issue 32), so they are kept apart from the keys the scenario reader turns into parameters;
# so is the endurance (minutes of flight: the dry run judges each flight's time against it,
# gcs_planner/dryrun/endurance.py).
# "firmware" is the former name of "autopilot", still read.
# The battery's energy (Wh), the power at cruise (W) and the fraction of the energy kept in
# reserve give the endurance when it is not stated (gcs_planner/dryrun/endurance.py).
AUTOPILOT_KEYS = (
    "max_climb_rate", "max_sink_rate", "autopilot", "firmware", "endurance",
    "battery_wh", "cruise_power_w", "battery_reserve",
)  # fmt: skip
# [environment]: the design wind ("SPEED[@FROM_DEG]" or a number of m/s), the design gust (m/s
# per horizontal axis: the derived flight reserve covers it), metres of position error per error
# unit, the landmarks' capture radius (metres, 3D), and the vertical turbulence the aircraft
# meets (sigma_w m/s or a level of MIL-F-8785C: sim/turbulence.py; the dry run flies it).
ENVIRONMENT_KEYS = ("wind", "gust", "error_unit", "capture_radius", "turbulence")
# [vehicle]: the aircraft. The turning radius and the climb limits may stand here or under
# [parameters]; cruise_airspeed with max_bank_angle gives the radius when it is not given.
VEHICLE_KEYS = (
    "turn_radius",
    "max_climb_angle",
    "max_descent_angle",
    "cruise_airspeed",
    "max_bank_angle",
    "leg_model",
    "reserve",
    "approach",
    "departure",
)
ORIGIN_KEYS = ("lat", "lon", "alt")
POINTS_SUFFIXES = (".csv", ".xlsx", ".geojson", ".json")


@dataclass(frozen=True)
class ScenarioSpec:
    """What a scenario TOML says, checked for types, unknown keys and ranges."""

    path: Path
    points: Path
    name: str | None = None
    parameters: dict[str, float] = field(default_factory=dict)
    parameter_lines: dict[str, int | None] = field(default_factory=dict)
    origin: Origin | None = None
    heading_at_a: tuple[float, float, float] | None = None
    # [vehicle] values (numbers, and leg_model as a string) and their lines
    vehicle: dict[str, object] = field(default_factory=dict)
    vehicle_lines: dict[str, int | None] = field(default_factory=dict)
    # [vehicle] rates and firmware, [environment] values: (value, line) each
    autopilot_terms: dict[str, tuple[object, int | None]] = field(default_factory=dict)
    environment: dict[str, tuple[object, int | None]] = field(default_factory=dict)


def key_line(text: str, table: str, key: str) -> int | None:
    """1-based line where ``key`` is set inside ``[table]`` ("" for the top level), if found."""
    current = ""
    assignment = re.compile(rf"""^\s*(?:{re.escape(key)}|"{re.escape(key)}")\s*=""")
    for number, line in enumerate(text.splitlines(), start=1):
        header = re.match(r"^\s*\[\s*([^\[\]]+?)\s*\]", line)
        if header:
            current = header.group(1)
        elif current == table and assignment.match(line):
            return number
    return None


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_origin(
    lat: object,
    lon: object,
    alt: object,
    *,
    file: str,
    rows: Mapping[str, int | None] | None = None,
) -> Origin:
    """An Origin from raw values, or InputError naming the bad one (``rows``: line per key)."""
    for name, value, bound in (("lat", lat, 90.0), ("lon", lon, 180.0), ("alt", alt, math.inf)):
        row = (rows or {}).get(name)
        if not _is_number(value) or not math.isfinite(value):
            raise InputError(
                f"must be a finite number (got {value!r})",
                file=file,
                row=row,
                field=f"origin.{name}",
            )
        if abs(value) > bound:
            raise InputError(
                f"must lie in [-{bound:g}, {bound:g}] degrees (got {value!r})",
                file=file,
                row=row,
                field=f"origin.{name}",
            )
    return Origin(float(lat), float(lon), float(alt))  # type: ignore[arg-type]


def check_heading(value: object, *, file: str, row: int | None) -> tuple[float, float, float]:
    """The unit vector of a heading given as three numbers, or InputError."""
    if (
        not isinstance(value, (list, tuple))
        or len(value) != 3
        or not all(_is_number(c) and math.isfinite(c) for c in value)
    ):
        raise InputError(
            f"must be three finite numbers [x, y, z] (got {value!r})",
            file=file,
            row=row,
            field="heading_at_a",
        )
    norm = math.hypot(*(float(c) for c in value))  # hypot: no overflow for large components
    if norm == 0.0 or not math.isfinite(norm):
        raise InputError(
            "must not be the zero vector (it gives no direction)",
            file=file,
            row=row,
            field="heading_at_a",
        )
    x, y, z = (float(c) / norm for c in value)
    return x, y, z


def _unknown(doc: dict, allowed: tuple[str, ...], table: str, file: str, text: str) -> None:
    unknown = [k for k in doc if k not in allowed]
    if unknown:
        prefix = f"{table}." if table else ""
        raise InputError(
            f"unknown key(s) {', '.join(repr(prefix + k) for k in unknown)} "
            f"(allowed: {', '.join(allowed)})",
            file=file,
            row=key_line(text, table, unknown[0]),
            field=prefix + unknown[0],
        )


def _table(doc: dict, key: str, file: str, text: str) -> dict:
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise InputError("must be a table", file=file, row=key_line(text, "", key), field=key)
    return value


def load_toml(path: Path) -> tuple[dict, str]:
    """The parsed document and its text (for line numbers), or InputError naming the file and,
    for a syntax error, its line."""
    file = str(path)
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise InputError("no such file", file=file) from None
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", file=file) from None
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text (offset {exc.start})", file=file) from None
    try:
        return tomllib.loads(text), text
    except tomllib.TOMLDecodeError as exc:
        found = re.search(r"line (\d+)", str(exc))
        raise InputError(
            f"TOML syntax error: {exc}", file=file, row=int(found.group(1)) if found else None
        ) from None


def read_scenario_toml(path: Path) -> ScenarioSpec:
    """Parse and check a scenario TOML; the points file must exist (it is not read here)."""
    file = str(path)
    doc, text = load_toml(path)

    _unknown(doc, TOP_KEYS, "", file, text)
    name = doc.get("name")
    if name is not None and not isinstance(name, str):
        raise InputError(
            "must be a string", file=file, row=key_line(text, "", "name"), field="name"
        )

    points_line = key_line(text, "", "points")
    if "points" not in doc:
        raise InputError(
            "missing key: the points file (.csv, .xlsx or .geojson), relative to this file",
            file=file,
            field="points",
        )
    if not isinstance(doc["points"], str) or not doc["points"].strip():
        raise InputError("must be a file name (string)", file=file, row=points_line, field="points")
    points = path.parent / doc["points"]
    if points.suffix.lower() not in POINTS_SUFFIXES:
        raise InputError(
            f"points file must be .csv, .xlsx or .geojson (got {doc['points']!r})",
            file=file,
            row=points_line,
            field="points",
        )
    if not points.is_file():
        what = "is a directory" if points.is_dir() else "does not exist"
        raise InputError(
            f"points file {str(points)!r} {what}", file=file, row=points_line, field="points"
        )

    table = _table(doc, "parameters", file, text)
    _unknown(table, PARAMETER_KEYS, "parameters", file, text)
    parameters: dict[str, float] = {}
    lines: dict[str, int | None] = {}
    for key, value in table.items():
        lines[key] = key_line(text, "parameters", key)
        if not _is_number(value):
            raise InputError(
                f"must be a number (got {value!r})", file=file, row=lines[key], field=key
            )
        parameters[key] = float(value)

    vehicle: dict[str, object] = {}
    vehicle_lines: dict[str, int | None] = {}
    terms: dict[str, tuple[object, int | None]] = {}
    environment: dict[str, tuple[object, int | None]] = {}
    if "environment" in doc:
        raw_env = _table(doc, "environment", file, text)
        _unknown(raw_env, ENVIRONMENT_KEYS, "environment", file, text)
        for key, value in raw_env.items():
            environment[key] = _term(value, key, "environment", file, text)
    if "vehicle" in doc:
        raw = dict(_table(doc, "vehicle", file, text))
        _unknown(raw, VEHICLE_KEYS + AUTOPILOT_KEYS, "vehicle", file, text)
        for key in AUTOPILOT_KEYS:
            if key in raw:
                terms[key] = _term(raw.pop(key), key, "vehicle", file, text)
        for key, value in raw.items():
            vehicle_lines[key] = key_line(text, "vehicle", key)
            if key == "leg_model":
                if not isinstance(value, str):
                    raise InputError(
                        f"must be a string (got {value!r})",
                        file=file,
                        row=vehicle_lines[key],
                        field=f"vehicle.{key}",
                    )
                vehicle[key] = value
            elif not _is_number(value):
                raise InputError(
                    f"must be a number (got {value!r})",
                    file=file,
                    row=vehicle_lines[key],
                    field=f"vehicle.{key}",
                )
            else:
                vehicle[key] = float(value)
            if key in parameters:
                raise InputError(
                    f"given twice: in [parameters] (line {lines[key]}) and in [vehicle]",
                    file=file,
                    row=vehicle_lines[key],
                    field=f"vehicle.{key}",
                )

    origin = None
    if "origin" in doc:
        raw = _table(doc, "origin", file, text)
        _unknown(raw, ORIGIN_KEYS, "origin", file, text)
        for key in ("lat", "lon"):
            if key not in raw:
                raise InputError(
                    "missing key (the origin needs lat and lon)",
                    file=file,
                    row=key_line(text, "", "origin"),
                    field=f"origin.{key}",
                )
        rows = {key: key_line(text, "origin", key) for key in ORIGIN_KEYS}
        origin = check_origin(raw["lat"], raw["lon"], raw.get("alt", 0.0), file=file, rows=rows)

    heading = None
    if "heading_at_a" in doc:
        heading = check_heading(
            doc["heading_at_a"], file=file, row=key_line(text, "", "heading_at_a")
        )

    return ScenarioSpec(
        path=path,
        points=points,
        name=name,
        parameters=parameters,
        parameter_lines=lines,
        origin=origin,
        heading_at_a=heading,
        vehicle=vehicle,
        vehicle_lines=vehicle_lines,
        autopilot_terms=terms,
        environment=environment,
    )


def _term(value: object, key: str, table: str, file: str, text: str) -> tuple[object, int | None]:
    """A [vehicle] autopilot term or an [environment] value, checked for its type and range:
    (value, line). Rates, the error unit and the capture radius are numbers > 0; the wind a
    number >= 0 or "SPEED[@FROM_DEG]"; the autopilot one of ``AUTOPILOTS``."""
    line = key_line(text, table, key)

    def fail(why: str) -> InputError:
        return InputError(why, file=file, row=line, field=f"{table}.{key}")

    if key in ("autopilot", "firmware"):
        if not isinstance(value, str) or value not in AUTOPILOTS:
            names = " or ".join(f'"{name}"' for name in AUTOPILOTS)
            raise fail(f"must be {names} (got {value!r})")
        return value, line
    if key == "wind":
        text_value = str(value) if _is_number(value) or isinstance(value, str) else None
        if text_value is None:
            raise fail(f'must be SPEED or "SPEED@FROM_DEG" (got {value!r})')
        speed, _, direction = text_value.partition("@")
        try:
            ok = float(speed) >= 0 and (not direction or math.isfinite(float(direction)))
        except ValueError:
            ok = False
        if not ok or not math.isfinite(float(speed)):
            raise fail(f'must be SPEED >= 0 m/s or "SPEED@FROM_DEG" (got {value!r})')
        return text_value, line
    if key == "turbulence":
        try:
            parse_turbulence(value if isinstance(value, str) or _is_number(value) else "?")
        except ValueError as exc:
            raise fail(str(exc)) from None
        return value, line
    if key == "battery_reserve":
        if not _is_number(value) or not 0.0 <= float(value) < 1.0:  # type: ignore[arg-type]
            raise fail(f"must be a fraction of the energy in [0, 1) (got {value!r})")
        return float(value), line  # type: ignore[arg-type]
    if key == "gust":
        if not _is_number(value) or not 0.0 <= float(value) <= 50.0:  # type: ignore[arg-type]
            raise fail(f"must be a speed in [0, 50] m/s (got {value!r})")
        return float(value), line  # type: ignore[arg-type]
    if not _is_number(value) or not (math.isfinite(float(value)) and float(value) > 0):  # type: ignore[arg-type]
        raise fail(f"must be a number > 0 (got {value!r})")
    return float(value), line  # type: ignore[arg-type]
