"""The scenario readers: the contest workbooks, CSV and TOML, overrides, and every bad input."""

from __future__ import annotations

import heapq
import math
import warnings
from pathlib import Path

import numpy as np
import openpyxl
import pytest
from support.paths import DATA, MISSIONS

from gcs_planner.aircraft.profile import DEFAULT_RESERVE_M
from gcs_planner.core.route import evaluate_route
from gcs_planner.errors import InputError
from gcs_planner.scenario.generate import DATASET1, random_scenario
from gcs_planner.scenario.model import PARAMETER_NAMES, Kind, Origin, Parameters, Scenario
from gcs_planner.scenario.readers import load_scenario

EXAMPLE = MISSIONS / "example"
REQUIRED = {k: getattr(DATASET1, k) for k in PARAMETER_NAMES}
LETTER = {Kind.A: "A", Kind.B: "B", Kind.V: "V", Kind.H: "H"}
HEADER = "id,x,y,z,kind,unreliable"
GOOD_ROWS = ["0,0,0,0,A,0", "1,100,0,0,V,1", "2,200,5,1,H,0", "3,300,0,0,B,0"]


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def csv_file(tmp_path: Path, rows: list[str], header: str = HEADER) -> Path:
    return write(tmp_path / "points.csv", "\n".join([header, *rows]) + "\n")


def toml_file(tmp_path: Path, body: str, name: str = "scenario.toml") -> Path:
    return write(tmp_path / name, body)


def scenario_to_csv(scenario: Scenario, path: Path, columns: list[str] | None = None) -> Path:
    columns = columns or HEADER.split(",")
    lines = [",".join(columns)]
    for i in range(scenario.n):
        cells = {
            "id": scenario.ids[i],
            "x": repr(float(scenario.xyz[i, 0])),
            "y": repr(float(scenario.xyz[i, 1])),
            "z": repr(float(scenario.xyz[i, 2])),
            "kind": LETTER[Kind(int(scenario.kind[i]))],
            "unreliable": str(int(scenario.unreliable[i])),
        }
        lines.append(",".join(cells[c] for c in columns))
    return write(path, "\n".join(lines) + "\n")


def expect_error(path: Path, overrides=None, *, row=None, field=None, file=None) -> InputError:
    """Load ``path``, expect InputError, and check the message names file, row and field."""
    with pytest.raises(InputError) as info:
        load_scenario(path, overrides if overrides is not None else REQUIRED)
    err = info.value
    message = str(err)
    assert err.file == (file if file is not None else str(path))
    assert err.file in message
    assert "\n" not in message
    if row is not None:
        assert err.row == row
        assert f"row {row}" in message
    if field is not None:
        assert err.field is not None and err.field.startswith(field)
        assert repr(err.field) in message
    return err


# --- the contest workbooks ------------------------------------------------------------------

FIGURES = {
    # README.md of the data: points, V, H, flagged, A, B
    "dataset1": (613, 305, 306, 148, (0, 50000, 5000), (100000, 59652.34, 5022.00)),
    "dataset2": (327, 158, 167, 82, (0, 50000, 5000), (100000, 74860.55, 5499.61)),
}


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_contest_workbook_matches_published_counts(name: str) -> None:
    points, n_v, n_h, flagged, a, b = FIGURES[name]
    path = DATA / f"{name}.xlsx"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the "Unknown extension" warning must be silenced
        scenario = load_scenario(path, REQUIRED)
    assert scenario.counts() == {"points": points, "V": n_v, "H": n_h, "unreliable": flagged}
    assert scenario.start == 0 and scenario.end == points - 1
    np.testing.assert_allclose(scenario.xyz[scenario.start], a, atol=0.005)
    np.testing.assert_allclose(scenario.xyz[scenario.end], b, atol=0.005)
    assert scenario.ids == tuple(str(i) for i in range(points))
    assert scenario.xyz.dtype == np.float64 and scenario.xyz.shape == (points, 3)
    assert scenario.kind.dtype == np.uint8 and scenario.unreliable.dtype == bool
    assert scenario.name == name and scenario.source == str(path)
    # airplane legs (the default with a turning radius): the default flight reserve
    assert scenario.params == Parameters(**REQUIRED, reserve=DEFAULT_RESERVE_M)
    assert scenario.origin is None and scenario.heading_at_a is None


def test_bare_workbook_without_parameters_names_every_missing_one() -> None:
    path = DATA / "dataset1.xlsx"
    err = expect_error(path, {}, field="alpha1")
    for name in PARAMETER_NAMES:
        assert name in str(err)
    assert "--alpha1" in str(err) and "TOML" in str(err)


def test_partial_overrides_name_only_the_missing_parameters(tmp_path: Path) -> None:
    path = csv_file(tmp_path, GOOD_ROWS)
    given = {**REQUIRED, "beta2": None, "theta": None}
    err = expect_error(path, given, field="beta2")
    assert "beta2" in str(err) and "theta" in str(err)
    assert "alpha1" not in str(err)


def test_workbook_written_like_the_contest_reads_with_varied_headers(tmp_path: Path) -> None:
    path = tmp_path / "mine.xlsx"
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["说明：a note"])
    sheet.append(
        [
            "编号",
            "X坐标 ( 单位:m )",
            "Y坐标（单位: m）",
            "z坐标",
            "校正点标记",
            "第三问点标记",
            None,
        ]
    )
    sheet.append([0, 0, 10, 20, "A点", 0])
    sheet.append([7.0, 1.5, 2.5, 3.5, 1, 1])
    sheet.append(["P8", 4, 5, 6, 0, 0])
    sheet.append([])
    sheet.append([9, 100, 0, 0, "B点", 0])
    book.save(path)
    scenario = load_scenario(path, REQUIRED)
    assert scenario.ids == ("0", "7", "P8", "9")
    assert scenario.kind.tolist() == [Kind.A, Kind.V, Kind.H, Kind.B]
    assert scenario.unreliable.tolist() == [False, True, False, False]
    np.testing.assert_array_equal(scenario.xyz[1], [1.5, 2.5, 3.5])


# --- CSV and TOML round trips ---------------------------------------------------------------


def test_csv_round_trip_keeps_values_and_order(tmp_path: Path) -> None:
    original = random_scenario(40, seed=3)
    # Shuffle the points so that A and B are not first and last: order must be the file's.
    order = np.random.default_rng(0).permutation(original.n)
    shuffled = Scenario(
        ids=tuple(f"p{original.ids[i]}" for i in order),
        xyz=original.xyz[order],
        kind=original.kind[order],
        unreliable=original.unreliable[order],
        params=original.params,
    )
    path = scenario_to_csv(
        shuffled, tmp_path / "pts.csv", ["kind", "z", "id", "unreliable", "y", "x"]
    )
    loaded = load_scenario(path, REQUIRED)
    assert loaded.ids == shuffled.ids
    np.testing.assert_array_equal(loaded.xyz, shuffled.xyz)  # repr round-trips exactly
    np.testing.assert_array_equal(loaded.kind, shuffled.kind)
    np.testing.assert_array_equal(loaded.unreliable, shuffled.unreliable)
    assert loaded.start == shuffled.start and loaded.end == shuffled.end
    assert loaded.name == "pts"


def test_csv_accepts_case_spaces_true_false_and_contest_codes(tmp_path: Path) -> None:
    rows = [
        "a, 0, 0, 0, a, false",
        "b,1,2,3, v ,TRUE",
        "c,1e3,-2.5,0,1,1",
        "d,4,5,6,0,0",
        "e,9,9,9,B点,0",
    ]
    path = write(tmp_path / "p.csv", "\ufeff ID , X,Y,Z,Kind,Unreliable\r\n" + "\r\n".join(rows))
    scenario = load_scenario(path, REQUIRED)
    assert scenario.ids == ("a", "b", "c", "d", "e")
    assert scenario.kind.tolist() == [Kind.A, Kind.V, Kind.V, Kind.H, Kind.B]
    assert scenario.unreliable.tolist() == [False, True, True, False, False]
    assert scenario.xyz[2].tolist() == [1000.0, -2.5, 0.0]


def test_toml_round_trip(tmp_path: Path) -> None:
    (tmp_path / "data").mkdir()
    csv_file(tmp_path / "data", GOOD_ROWS)
    path = toml_file(
        tmp_path,
        """
name = "trial"
points = "data/points.csv"
heading_at_a = [3, 4, 0]
[parameters]
alpha1 = 21
alpha2 = 12.5
beta1 = 19
beta2 = 24
theta = 28
delta = 0.002
turn_radius = 150
p_success = 0.7
fail_residual = 4
[origin]
lat = 30.5
lon = 123.5
alt = 12.0
""",
    )
    scenario = load_scenario(path)
    assert scenario.name == "trial" and scenario.source == str(path)
    assert scenario.params == Parameters(
        21, 12.5, 19, 24, 28, 0.002, 150, 0.7, 4, reserve=DEFAULT_RESERVE_M
    )
    assert scenario.origin == Origin(30.5, 123.5, 12.0)
    assert scenario.heading_at_a == pytest.approx((0.6, 0.8, 0.0))
    assert scenario.ids == ("0", "1", "2", "3")
    assert scenario.unreliable.tolist() == [False, True, False, False]


def test_toml_defaults_and_workbook_points(tmp_path: Path) -> None:
    body = f'points = "{(DATA / "dataset2.xlsx").as_posix()}"\n[parameters]\n'
    body += "\n".join(f"{k} = {v}" for k, v in REQUIRED.items())
    scenario = load_scenario(toml_file(tmp_path, body, "d2.toml"))
    defaults = Parameters(1, 1, 1, 1, 1, 1)
    assert scenario.params.turn_radius == defaults.turn_radius
    assert scenario.params.p_success == defaults.p_success
    assert scenario.params.fail_residual == defaults.fail_residual
    assert scenario.name == "d2" and scenario.n == 327
    assert scenario.origin is None and scenario.heading_at_a is None


def test_overrides_win_over_the_toml_and_none_is_ignored(tmp_path: Path) -> None:
    csv_file(tmp_path, GOOD_ROWS)
    body = 'points = "points.csv"\nheading_at_a = [1, 0, 0]\n[parameters]\n'
    body += "\n".join(f"{k} = {v}" for k, v in REQUIRED.items()) + "\nturn_radius = 300\n"
    body += "[origin]\nlat = 10\nlon = 20\n"
    path = toml_file(tmp_path, body)
    overrides = {
        "alpha1": 40.0,
        "delta": 0.0005,
        "turn_radius": 0.0,
        "theta": None,
        "p_success": None,
        "heading_at_a": (0.0, 2.0, 0.0),
        "origin": Origin(31.0, 124.0, 5.0),
    }
    scenario = load_scenario(path, overrides)
    assert scenario.params.alpha1 == 40.0 and scenario.params.delta == 0.0005
    assert scenario.params.turn_radius == 0.0
    assert scenario.params.theta == REQUIRED["theta"]  # None left the file's value
    assert scenario.params.p_success == 0.8
    assert scenario.heading_at_a == (0.0, 1.0, 0.0)
    assert scenario.origin == Origin(31.0, 124.0, 5.0)


def test_unknown_override_key_is_a_programming_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="alpha3"):
        load_scenario(csv_file(tmp_path, GOOD_ROWS), {**REQUIRED, "alpha3": 1.0})


# --- the bundled example --------------------------------------------------------------------


def _a_feasible_route(scenario: Scenario) -> tuple[int, ...] | None:
    """A short straight-leg route, found best-first over coarsened error states (any route it
    returns is checked exactly; coarsening can only make it miss one)."""
    p = scenario.params
    heap: list[tuple[float, float, float, tuple[int, ...]]] = [(0.0, 0.0, 0.0, (scenario.start,))]
    settled: set[tuple[int, int, int]] = set()
    while heap:
        length, dv, dh, path = heapq.heappop(heap)
        here = path[-1]
        if here == scenario.end:
            return path
        key = (here, int(dv // 250), int(dh // 250))
        if key in settled:
            continue
        settled.add(key)
        for j in range(scenario.n):
            kind = Kind(int(scenario.kind[j]))
            if j in path or kind == Kind.A:
                continue
            d = float(np.linalg.norm(scenario.xyz[j] - scenario.xyz[here]))
            v_lim, h_lim = p.limits_m(kind)
            if dv + d > v_lim or dh + d > h_lim:
                continue
            v = 0.0 if kind == Kind.V else dv + d
            h = 0.0 if kind == Kind.H else dh + d
            heapq.heappush(heap, (length + d, v, h, (*path, j)))
    return None


def test_bundled_example_loads_and_has_feasible_routes_with_margin() -> None:
    scenario = load_scenario(EXAMPLE / "scenario.toml")
    assert scenario.name == "example"
    # the aircraft the example states (missions/README.md): 200 m turns, 15 deg climbs
    assert scenario.params == Parameters(
        25, 15, 20, 25, 30, 0.001, 200, 0.8, 5, max_climb_angle=15.0, max_descent_angle=15.0,
        reserve=DEFAULT_RESERVE_M,
    )  # fmt: skip
    assert scenario.cruise_airspeed == 25.0
    assert scenario.origin == Origin(30.5, 123.5, 0.0)
    counts = scenario.counts()
    assert 50 <= counts["points"] <= 80 and counts["unreliable"] > 0
    assert counts["V"] > 0 and counts["H"] > 0
    # Feasible even with 10 % faster error growth, so turns of 200 m radius cannot break it.
    tighter = scenario.with_params(delta=0.0011)
    route = _a_feasible_route(tighter)
    assert route is not None
    assert evaluate_route(tighter, route).feasible


# --- bad inputs: each a one-line InputError naming file, row, field ---------------------------


@pytest.mark.parametrize(
    ("rows", "row", "field", "words"),
    [
        (["1,1,0,0,V,0", "3,3,0,0,B,0"], 1, "kind", "no start"),
        (["0,0,0,0,A,0", "1,1,0,0,V,0"], 1, "kind", "no end"),
        (["0,0,0,0,A,0", "1,1,0,0,a,0", "3,3,0,0,B,0"], 3, "kind", "more than one start"),
        (["0,0,0,0,A,0", "1,1,0,0,B,0", "3,3,0,0,B,0"], 4, "kind", "more than one end"),
        (["0,0,0,0,A,0", "1,1,0,0,V,0", "1,2,0,0,H,0", "3,3,0,0,B,0"], 4, "id", "duplicate"),
        (["0,0,0,0,A,0", " ,1,0,0,V,0", "3,3,0,0,B,0"], 3, "id", "missing"),
        (["0,0,0,0,A,0", "1,abc,0,0,V,0", "3,3,0,0,B,0"], 3, "x", "not a number"),
        (["0,0,0,0,A,0", "1,1,nan,0,V,0", "3,3,0,0,B,0"], 3, "y", "finite"),
        (["0,0,0,0,A,0", "1,1,0,-inf,V,0", "3,3,0,0,B,0"], 3, "z", "finite"),
        (["0,0,0,0,A,0", "1,1,0,1e999,V,0", "3,3,0,0,B,0"], 3, "z", "finite"),
        (["0,0,0,0,A,0", "1,1,0,,V,0", "3,3,0,0,B,0"], 3, "z", "missing"),
        (["0,0,0,0,A,0", "1,1,0,0,Q,0", "3,3,0,0,B,0"], 3, "kind", "unknown kind"),
        (["0,0,0,0,A,0", "1,1,0,0,V,2", "3,3,0,0,B,0"], 3, "unreliable", "0 or 1"),
        (["0,0,0,0,A,0", "1,1,0,0,V,yes", "3,3,0,0,B,0"], 3, "unreliable", "0 or 1"),
        (["0,0,0,0,A,1", "1,1,0,0,V,0", "3,3,0,0,B,0"], 2, "unreliable", "A point"),
        (["0,0,0,0,A,0", "1,1,0,0,V,0", "3,3,0,0,B,1"], 4, "unreliable", "B point"),
        (["0,0,0,0,A,0", "1,1,0,0,V", "3,3,0,0,B,0"], 3, None, "expected 6 fields"),
    ],
)
def test_bad_csv_rows(tmp_path: Path, rows, row, field, words) -> None:
    err = expect_error(csv_file(tmp_path, rows), row=row, field=field)
    assert words in str(err)


def test_blank_lines_do_not_shift_row_numbers(tmp_path: Path) -> None:
    path = write(tmp_path / "p.csv", f"{HEADER}\n\n0,0,0,0,A,0\n\n1,x,0,0,V,0\n")
    expect_error(path, row=5, field="x")


@pytest.mark.parametrize(
    ("header", "field", "words"),
    [
        ("id,x,y,z,kind", "unreliable", "missing column"),
        ("id,x,y,z,kind,unreliable,note", "note", "unknown column"),
        ("id,x,y,z,kind,unrelaible", "unreliable", "missing column"),
        ("id,x,x,z,kind,unreliable", "x", "twice"),
    ],
)
def test_bad_csv_header(tmp_path: Path, header, field, words) -> None:
    err = expect_error(csv_file(tmp_path, GOOD_ROWS, header=header), row=1, field=field)
    assert words in str(err)


def test_empty_csv(tmp_path: Path) -> None:
    err = expect_error(write(tmp_path / "e.csv", " \n\n"))
    assert "empty" in str(err)


def test_header_only_csv(tmp_path: Path) -> None:
    err = expect_error(write(tmp_path / "h.csv", f"\n{HEADER}\n\n"), row=2)
    assert "header only" in str(err)


def test_non_utf8_csv(tmp_path: Path) -> None:
    path = tmp_path / "latin.csv"
    path.write_bytes(f"{HEADER}\n0,0,0,0,A,0\n".encode() + "1,0,0,0,V,0 # café\n".encode("latin-1"))
    err = expect_error(path, row=3)
    assert "UTF-8" in str(err)


def test_missing_file_and_directory_and_unknown_suffix(tmp_path: Path) -> None:
    assert "no such file" in str(expect_error(tmp_path / "nope.csv"))
    folder = tmp_path / "folder.csv"
    folder.mkdir()
    assert "directory" in str(expect_error(folder))
    assert ".json" in str(expect_error(write(tmp_path / "s.json", "{}")))


def _workbook(path: Path, rows: list[list[object]], title: str | None = None) -> Path:
    book = openpyxl.Workbook()
    sheet = book.active
    if title:
        sheet.title = title
    for row in rows:
        sheet.append(row)
    book.save(path)
    return path


CONTEST_HEADER = [
    "编号",
    "X坐标（单位: m）",
    "Y坐标（单位:m）",
    "Z坐标（单位: m）",
    "校正点类型",
    "第三问点标记",
]


def test_workbook_with_wrong_sheet(tmp_path: Path) -> None:
    path = _workbook(tmp_path / "w.xlsx", [["month", "sales"], ["jan", 3]], title="Sales")
    err = expect_error(path, row=2, field="id")
    assert "header" in str(err)


def test_workbook_with_a_missing_column(tmp_path: Path) -> None:
    header = [h for h in CONTEST_HEADER if not h.startswith("Z")]
    path = _workbook(tmp_path / "w.xlsx", [["note"], header, [0, 0, 0, "A点", 0]])
    err = expect_error(path, row=2, field="z")
    assert "missing column" in str(err) and "Z坐标" in str(err)


def test_workbook_bad_cell_names_spreadsheet_row_and_column(tmp_path: Path) -> None:
    rows = [["note"], CONTEST_HEADER, [0, 0, 0, 0, "A点", 0], [1, 5, "?", 0, 1, 0]]
    rows.append([2, 9, 9, 9, "B点", 0])
    err = expect_error(_workbook(tmp_path / "w.xlsx", rows), row=4, field="y")
    assert "column C" in str(err)


def test_workbook_unknown_type_code(tmp_path: Path) -> None:
    rows = [["note"], CONTEST_HEADER, [0, 0, 0, 0, "A点", 0], [1, 5, 5, 0, 2, 0]]
    rows.append([2, 9, 9, 9, "B点", 0])
    err = expect_error(_workbook(tmp_path / "w.xlsx", rows), row=4, field="kind")
    assert "'2'" in str(err) or "2" in err.reason


def test_empty_and_header_only_workbooks(tmp_path: Path) -> None:
    assert "empty" in str(expect_error(_workbook(tmp_path / "e.xlsx", [])))
    err = expect_error(_workbook(tmp_path / "h.xlsx", [["note"], CONTEST_HEADER]), row=2)
    assert "header only" in str(err)


def test_file_that_is_not_a_workbook(tmp_path: Path) -> None:
    err = expect_error(write(tmp_path / "fake.xlsx", "id,x\n"))
    assert "workbook" in str(err)


# --- bad parameters -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "value"),
    [("alpha1", 0), ("alpha2", -1), ("beta1", math.nan), ("theta", math.inf), ("delta", 0.0),
     ("delta", -0.001), ("turn_radius", -5), ("p_success", 1.5), ("fail_residual", -1)],
)  # fmt: skip
def test_bad_parameter_from_the_command_line(tmp_path: Path, name: str, value: float) -> None:
    path = csv_file(tmp_path, GOOD_ROWS)
    err = expect_error(path, {**REQUIRED, name: value}, field=name, file="command line")
    assert name in err.reason


def test_non_numeric_override(tmp_path: Path) -> None:
    expect_error(
        csv_file(tmp_path, GOOD_ROWS),
        {**REQUIRED, "beta1": "x"},
        field="beta1",
        file="command line",
    )


def _toml_with(tmp_path: Path, extra_top: str = "", parameters: str = "", origin: str = "") -> Path:
    csv_file(tmp_path, GOOD_ROWS)
    body = f'name = "t"\npoints = "points.csv"\n{extra_top}[parameters]\n'
    body += "\n".join(f"{k} = {v}" for k, v in REQUIRED.items()) + "\n" + parameters
    if origin:
        body += f"[origin]\n{origin}"
    return toml_file(tmp_path, body)


@pytest.mark.parametrize(("name", "value"), [("alpha1", "0"), ("beta2", "-3"), ("delta", "0.0")])
def test_bad_parameter_in_the_toml_names_its_line(tmp_path: Path, name: str, value: str) -> None:
    path = _toml_with(tmp_path, parameters="turn_radius = 100\n")
    text = path.read_text().replace(f"{name} = {REQUIRED[name]}", f"{name} = {value}")
    write(path, text)
    line = text.splitlines().index(f"{name} = {value}") + 1
    expect_error(path, {}, row=line, field=name)


def test_string_parameter_in_the_toml(tmp_path: Path) -> None:
    path = _toml_with(tmp_path, parameters='turn_radius = "200"\n')
    err = expect_error(path, {}, row=10, field="turn_radius")
    assert "number" in str(err)


@pytest.mark.parametrize(
    ("extra_top", "parameters", "origin", "row", "field"),
    [
        ("colour = 1\n", "", "", 3, "colour"),
        ("", "alpah1 = 3\n", "", 10, "parameters.alpah1"),
        ("", "", "lat = 30\nlon = 120\nheight = 3\n", 13, "origin.height"),
    ],
)
def test_unknown_toml_keys_are_named(tmp_path, extra_top, parameters, origin, row, field) -> None:
    err = expect_error(
        _toml_with(tmp_path, extra_top, parameters, origin), {}, row=row, field=field
    )
    assert "unknown key" in str(err)


@pytest.mark.parametrize(
    ("origin", "field"),
    [("lat = 91\nlon = 0\n", "origin.lat"), ("lat = 0\nlon = -180.5\n", "origin.lon"),
     ("lat = nan\nlon = 0\n", "origin.lat"), ("lat = 0\nlon = 0\nalt = inf\n", "origin.alt"),
     ("lat = 0\n", "origin.lon"), ('lat = "30N"\nlon = 0\n', "origin.lat")],
)  # fmt: skip
def test_bad_origin(tmp_path: Path, origin: str, field: str) -> None:
    expect_error(_toml_with(tmp_path, origin=origin), {}, field=field)


def test_bad_origin_override(tmp_path: Path) -> None:
    path = csv_file(tmp_path, GOOD_ROWS)
    overrides = {**REQUIRED, "origin": Origin(12.0, 200.0)}
    expect_error(path, overrides, field="origin.lon", file="command line")


@pytest.mark.parametrize("heading", ["[0, 0, 0]", "[1, 0]", '["a", 0, 0]', "[nan, 0, 1]"])
def test_bad_heading(tmp_path: Path, heading: str) -> None:
    expect_error(
        _toml_with(tmp_path, f"heading_at_a = {heading}\n"), {}, row=3, field="heading_at_a"
    )


def test_zero_heading_override(tmp_path: Path) -> None:
    path = csv_file(tmp_path, GOOD_ROWS)
    overrides = {**REQUIRED, "heading_at_a": (0.0, 0.0, 0.0)}
    err = expect_error(path, overrides, field="heading_at_a", file="command line")
    assert "zero" in str(err)


def test_toml_syntax_error_names_the_line(tmp_path: Path) -> None:
    path = toml_file(tmp_path, 'points = "points.csv"\n[parameters]\nalpha1 = = 3\n')
    err = expect_error(path, {}, row=3)
    assert "syntax" in str(err)


def test_toml_pointing_to_a_missing_points_file(tmp_path: Path) -> None:
    path = toml_file(tmp_path, '# comment\npoints = "gone.csv"\n')
    err = expect_error(path, {}, row=2, field="points")
    assert "gone.csv" in str(err)


def test_toml_without_points_or_with_a_bad_points_type(tmp_path: Path) -> None:
    expect_error(toml_file(tmp_path, 'name = "x"\n'), {}, field="points")
    write(tmp_path / "p.txt", "")
    expect_error(toml_file(tmp_path, 'points = "p.txt"\n'), {}, row=1, field="points")


def test_toml_without_parameters_takes_them_from_flags(tmp_path: Path) -> None:
    csv_file(tmp_path, GOOD_ROWS)
    path = toml_file(tmp_path, 'points = "points.csv"\n')
    assert load_scenario(path, REQUIRED).params == Parameters(**REQUIRED, reserve=DEFAULT_RESERVE_M)
    err = expect_error(path, {"alpha1": 1.0}, field="alpha2")
    assert "[parameters]" in str(err) and "alpha1" not in err.reason.split(":")[0]


def test_errors_in_the_points_file_of_a_toml_name_the_points_file(tmp_path: Path) -> None:
    path = _toml_with(tmp_path)
    write(tmp_path / "points.csv", f"{HEADER}\n0,0,0,0,A,0\n1,0,0,0,B,0\n2,0,0,0,B,0\n")
    expect_error(path, {}, row=4, field="kind", file=str(tmp_path / "points.csv"))


def test_a_name_too_long_for_the_file_system(tmp_path: Path) -> None:
    err = expect_error(tmp_path / ("x" * 300 + ".csv"))
    assert "cannot open" in str(err)


def test_heading_override_as_an_array(tmp_path: Path) -> None:
    path = csv_file(tmp_path, GOOD_ROWS)
    heading = np.array([0, 0, -4])
    scenario = load_scenario(path, {**REQUIRED, "heading_at_a": heading})
    assert scenario.heading_at_a == (0.0, 0.0, -1.0)


def test_the_flight_reserve_defaults_by_leg_model_and_is_checked(tmp_path: Path) -> None:
    """Airplane legs keep the default reserve (capped at a share of the tightest limit); cs3d and
    straight legs plan the contest's model without one; a given reserve wins; a reserve that
    eats a whole limit is refused naming the field."""
    path = DATA / "dataset1.xlsx"
    assert load_scenario(path, REQUIRED).params.reserve == DEFAULT_RESERVE_M
    assert load_scenario(path, {**REQUIRED, "leg_model": "cs3d"}).params.reserve == 0.0
    assert load_scenario(path, {**REQUIRED, "turn_radius": 0.0}).params.reserve == 0.0
    assert load_scenario(path, {**REQUIRED, "reserve": 0.0}).params.reserve == 0.0
    assert load_scenario(path, {**REQUIRED, "reserve": 75.0}).params.reserve == 75.0
    tight = {**REQUIRED, "alpha2": 1.0, "delta": 0.001}  # 1,000 m: 5 % of it is the default
    assert load_scenario(path, tight).params.reserve == pytest.approx(50.0)
    err = expect_error(path, {**REQUIRED, "reserve": 15000.0}, field="reserve", file="command line")
    assert "below the tightest limit" in str(err)
    params = load_scenario(path, {**REQUIRED, "reserve": 100.0}).params
    assert params.limits_m(Kind.V) == pytest.approx((25_000 - 100, 15_000 - 100))
    assert params.flown().limits_m(Kind.V) == pytest.approx((25_000, 15_000))
