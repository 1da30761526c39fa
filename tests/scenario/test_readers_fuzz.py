"""Fuzzing the readers: any file either loads into a Scenario true to the file, or raises
InputError — never another exception (a traceback must not reach the user)."""

from __future__ import annotations

import csv
import datetime as dt
import io
import math
import tempfile
import unicodedata
from dataclasses import fields
from pathlib import Path

import numpy as np
import openpyxl
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcs_planner.aircraft.profile import DEFAULT_RESERVE_M, DEFAULT_RESERVE_MAX_SHARE
from gcs_planner.errors import InputError
from gcs_planner.scenario.generate import DATASET1
from gcs_planner.scenario.model import PARAMETER_NAMES, Kind, Origin, Parameters, Scenario
from gcs_planner.scenario.readers import MAX_COORDINATE, SAME_POINT_M, load_scenario

REQUIRED = {k: getattr(DATASET1, k) for k in PARAMETER_NAMES}
COLUMNS = ["id", "x", "y", "z", "kind", "unreliable"]
FUZZ = settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)

# The documented vocabularies (missions/README.md), stated here independently of the reader.
KIND_WORDS = {"A": Kind.A, "A点": Kind.A, "B": Kind.B, "B点": Kind.B,
              "V": Kind.V, "1": Kind.V, "H": Kind.H, "0": Kind.H}  # fmt: skip
FLAG_WORDS = {"0": False, "1": True, "0.0": False, "1.0": True, "TRUE": True, "FALSE": False}


def load_or_input_error(path: Path) -> Scenario | None:
    try:
        return load_scenario(path, REQUIRED)
    except InputError as err:
        assert str(err) and "\n" not in str(err)
        return None


# --- structured CSV: rows of valid and corrupted cells, with an independent oracle ---------

any_ids = st.one_of(
    st.integers(0, 30).map(str),
    st.text(st.characters(blacklist_categories=("Cs",)), max_size=6),
)
good_numbers = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.integers(-(10**6), 10**6).map(str),
)
any_numbers = st.one_of(
    good_numbers,
    st.sampled_from(["", " ", "abc", "nan", "inf", "-inf", "1e999", "0x10", "1,5", "--1", "1e"]),
)
any_kinds = st.sampled_from(
    [
        "A",
        "B",
        "V",
        "H",
        "a",
        "v",
        " h ",
        "1",
        "0",
        "A点",
        "B点",
        "",
        "X",
        "2",
        "AB",
        "1.5",
        "start",
    ]
)
good_flags = st.sampled_from(["0", "1", "true", "FALSE", " 1 ", "0.0"])
any_flags = st.one_of(good_flags, st.sampled_from(["", "2", "yes", "-1"]))
CORRUPT = {"id": any_ids, "x": any_numbers, "y": any_numbers, "z": any_numbers,
           "kind": any_kinds, "unreliable": any_flags}  # fmt: skip


@st.composite
def rows(draw) -> list[dict[str, str]]:
    """A valid point table (A, some V/H, B, in random order) with a few cells corrupted, rows
    dropped or duplicated now and then, so that both outcomes occur often."""
    n = draw(st.integers(0, 6))
    kinds = ["A", "B", *draw(st.lists(st.sampled_from(["V", "H", "v", "1", "0"]), min_size=n,
                                      max_size=n))]  # fmt: skip
    kinds = draw(st.permutations(kinds))
    records = []
    for i, kind in enumerate(kinds):
        flag = "0" if kind in ("A", "B") else draw(good_flags)
        xyz = [draw(good_numbers) for _ in range(3)]
        records.append(dict(zip(COLUMNS, [f"p{i}", *xyz, kind, flag], strict=True)))
    for _ in range(draw(st.integers(0, 3))):
        action = draw(st.sampled_from(["cell", "cell", "drop", "duplicate"]))
        i = draw(st.integers(0, len(records) - 1)) if records else None
        if i is None:
            break
        if action == "cell":
            column = draw(st.sampled_from(COLUMNS))
            records[i][column] = draw(CORRUPT[column])
        elif action == "drop":
            del records[i]
        else:
            records.insert(draw(st.integers(0, len(records))), dict(records[i]))
    return records


def _number(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def expected_points(records: list[dict[str, str]]) -> list[tuple] | None:
    """What a correct reader must produce from these records, or None if the file is invalid."""
    out = []
    seen = set()
    for record in records:
        cells = {k: v.strip() for k, v in record.items()}
        if not any(cells.values()):
            continue  # a blank record is skipped like a blank line
        point_id = cells["id"]
        xyz = [_number(cells[c]) for c in "xyz"]
        # The reader's bounds (readers.MAX_COORDINATE): farther is a typo, not a place.
        xyz = [v if v is None or abs(v) <= lim else None for v, lim in zip(xyz, MAX_COORDINATE)]
        kind = KIND_WORDS.get(unicodedata.normalize("NFKC", cells["kind"]).upper())
        flag = FLAG_WORDS.get(cells["unreliable"].upper())
        if not point_id or point_id in seen or None in xyz or kind is None or flag is None:
            return None
        if flag and kind in (Kind.A, Kind.B):
            return None
        seen.add(point_id)
        out.append((point_id, xyz, kind, flag))
    if not out or [p[2] for p in out].count(Kind.A) != 1 or [p[2] for p in out].count(Kind.B) != 1:
        return None
    a, b = (next(p[1] for p in out if p[2] == end) for end in (Kind.A, Kind.B))
    if math.dist(a, b) < SAME_POINT_M:
        return None  # A and B in one place: a 0 m mission
    return out


@FUZZ
@given(records=rows(), order=st.permutations(COLUMNS))
def test_structured_csv_loads_exactly_when_valid(tmp_path_factory, records, order) -> None:
    buffer = io.StringIO(newline="")
    writer = csv.writer(buffer)
    writer.writerow(order)
    for record in records:
        writer.writerow([record[c] for c in order])
    path = tmp_path_factory.mktemp("csv") / "points.csv"
    path.write_text(buffer.getvalue(), encoding="utf-8", newline="")
    expected = expected_points(records)
    scenario = load_or_input_error(path)
    if expected is None:
        assert scenario is None
        return
    assert scenario is not None
    assert list(scenario.ids) == [p[0] for p in expected]
    np.testing.assert_array_equal(scenario.xyz, np.array([p[1] for p in expected]).reshape(-1, 3))
    assert scenario.kind.tolist() == [int(p[2]) for p in expected]
    assert scenario.unreliable.tolist() == [p[3] for p in expected]


# --- unstructured input: random bytes and text -------------------------------------------


@FUZZ
@given(data=st.binary(max_size=300))
def test_random_bytes_never_crash(tmp_path_factory, data: bytes) -> None:
    path = tmp_path_factory.mktemp("bytes") / "points.csv"
    path.write_bytes(b"id,x,y,z,kind,unreliable\n" + data)
    scenario = load_or_input_error(path)
    if scenario is not None:
        assert scenario.n >= 2 and len(set(scenario.ids)) == scenario.n
        assert np.isfinite(scenario.xyz).all()


@FUZZ
@given(
    text=st.text(alphabet=st.sampled_from(list('0123456789.,-\n\r" AaBbVvHe#x点')), max_size=200)
)
def test_random_csv_like_text_never_crashes(tmp_path_factory, text: str) -> None:
    path = tmp_path_factory.mktemp("text") / "points.csv"
    path.write_text("id,x,y,z,kind,unreliable\n0,0,0,0,A,0\n" + text, encoding="utf-8")
    scenario = load_or_input_error(path)
    if scenario is not None:
        assert scenario.ids[0] == "0" and scenario.kind[0] == Kind.A
        assert int(np.sum(scenario.kind == Kind.B)) == 1


@FUZZ
@given(text=st.text(max_size=200))
def test_random_toml_text_never_crashes(tmp_path_factory, text: str) -> None:
    folder = tmp_path_factory.mktemp("toml")
    (folder / "points.csv").write_text("id,x,y,z,kind,unreliable\n0,0,0,0,A,0\n1,1,1,1,B,0\n")
    path = folder / "scenario.toml"
    path.write_text('points = "points.csv"\n' + text, encoding="utf-8")
    load_or_input_error(path)


toml_values = st.one_of(
    st.floats(0.001, 1.0),  # valid for every parameter, so that valid files are common
    st.floats(width=32),
    st.integers(-3, 50),
    st.booleans(),
    st.sampled_from(["x", "25"]),
)
PARAMETER_KEYS = [f.name for f in fields(Parameters)]


def toml_literal(value: object) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)  # nan, inf, -inf are TOML literals too
    return repr(value)


def expected_value(key: str, values: dict[str, object]) -> float:
    """What a scenario TOML without a [vehicle] table (airplane legs) loads for ``key``: the
    file's value, else the default; the flight reserve's default is 200 m on airplane legs with
    a turning radius, capped at 5 % of the tightest limit in metres."""
    if key in values:
        return values[key]  # type: ignore[return-value]
    if key == "reserve" and float(values.get("turn_radius", DATASET1.turn_radius)) > 0:
        tightest = min(float(values[k]) for k in PARAMETER_NAMES[:5]) / float(values["delta"])
        return min(DEFAULT_RESERVE_M, DEFAULT_RESERVE_MAX_SHARE * tightest)
    return getattr(DATASET1, key)


def parameters_valid(values: dict[str, object]) -> bool:
    if not set(PARAMETER_NAMES) <= set(values) or not set(values) <= set(PARAMETER_KEYS):
        return False
    if any(isinstance(v, (bool, str)) for v in values.values()):
        return False
    return not Parameters(**{k: float(v) for k, v in values.items()}).validate()


@FUZZ
@given(
    changes=st.dictionaries(st.sampled_from([*PARAMETER_KEYS, "alpah1"]), toml_values, max_size=2),
    removed=st.sets(st.sampled_from(PARAMETER_KEYS), max_size=1),
    origin=st.none()
    | st.tuples(st.floats(-90, 90), st.floats(-180, 180), st.floats(-100, 100))
    | st.tuples(st.floats(-200, 200), st.floats(-400, 400), st.floats(width=32)),
    heading=st.none() | st.lists(st.sampled_from([0.0, -1.0, 2.5, 1e-300, 1e300]), min_size=3,
                                 max_size=3),
)  # fmt: skip
def test_structured_toml_loads_exactly_when_valid(
    tmp_path_factory, changes, removed, origin, heading
) -> None:
    values = {k: v for k, v in {**REQUIRED, **changes}.items() if k not in removed}
    folder = tmp_path_factory.mktemp("toml")
    (folder / "points.csv").write_text("id,x,y,z,kind,unreliable\n0,0,0,0,A,0\n1,1,1,1,B,0\n")
    lines = ['points = "points.csv"']
    if heading is not None:
        lines.append(f"heading_at_a = [{', '.join(map(toml_literal, heading))}]")
    lines.append("[parameters]")
    lines += [f"{k} = {toml_literal(v)}" for k, v in values.items()]
    if origin is not None:
        lines += [
            "[origin]",
            *(
                f"{k} = {toml_literal(v)}"
                for k, v in zip("lat lon alt".split(), origin, strict=True)
            ),
        ]
    path = folder / "scenario.toml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")

    valid = parameters_valid(values)
    if origin is not None:
        lat, lon, alt = origin
        valid &= abs(lat) <= 90 and abs(lon) <= 180 and math.isfinite(alt)
    if heading is not None:
        valid &= any(heading)
    try:
        scenario = load_scenario(path)
    except InputError:
        assert not valid
        return
    assert valid
    for key in PARAMETER_KEYS:
        assert getattr(scenario.params, key) == expected_value(key, values)
    assert scenario.origin == (None if origin is None else Origin(*origin))
    if heading is not None:
        norm = math.hypot(*heading)
        assert scenario.heading_at_a == tuple(c / norm for c in heading)


# --- the workbook reader, lightly: random cell types under a contest header ---------------

cell = st.one_of(
    st.none(),
    st.integers(-5, 5),
    st.floats(allow_nan=False, allow_infinity=False, width=32),
    st.booleans(),
    st.sampled_from(["A点", "B点", "V", "x", "", " ", "1", "0", "nan"]),
    st.datetimes(min_value=dt.datetime(2000, 1, 1), max_value=dt.datetime(2030, 1, 1)),
)
sheet_rows = st.lists(st.lists(cell, min_size=0, max_size=7), max_size=6)
HEADER = [
    "编号",
    "X坐标（单位: m）",
    "Y坐标（单位:m）",
    "Z坐标（单位: m）",
    "校正点类型",
    "第三问点标记",
]


def _blank(value: object) -> bool:
    return value is None or (isinstance(value, str) and not value.strip())


@settings(max_examples=25, deadline=None)
@given(body=sheet_rows, with_header=st.booleans(), with_end=st.booleans())
def test_random_workbooks_never_crash(body, with_header: bool, with_end: bool) -> None:
    rows = [[0, 0, 0, 0, "A点", 0], *body] + ([[99, 1.5, 2, 3, "B点", 0]] if with_end else [])
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "w.xlsx"
        book = openpyxl.Workbook()
        sheet = book.active
        sheet.append(["note"])
        if with_header:
            sheet.append(HEADER)
        for row in rows:
            sheet.append(row)
        book.save(path)
        scenario = load_or_input_error(path)
    if scenario is not None:
        assert with_header
        # Rows blank in the six columns are skipped; every other row is a point, in order.
        kept = [r for r in rows if not all(_blank(c) for c in r[:6])]
        assert scenario.n == len(kept)
        assert scenario.ids[0] == "0" and scenario.kind[0] == Kind.A
        assert np.isfinite(scenario.xyz).all()
        np.testing.assert_array_equal(scenario.xyz, [[float(c) for c in r[1:4]] for r in kept])
