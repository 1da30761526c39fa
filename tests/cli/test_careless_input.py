"""Careless input through the real command line: a 0 m mission, a front over fewer objectives,
a damaged plan.json, an --out that contradicts --format or names a missing folder, and flags
out of range (link waits, --max-corrections, --speedup). Each is one line on stderr naming the
file or flag (and field), exit 2, no traceback, and nothing written."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
from gcs_planner.sim.vehicle import free_udp_port
from support.paths import MISSIONS
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.cli import main
from gcs_planner.errors import InputError
from gcs_planner.scenario.readers import load_scenario

COAST = MISSIONS / "coast" / "scenario.toml"  # plans in about 3 s
LIMITS = {"alpha1": 25, "alpha2": 15, "beta1": 20, "beta2": 25, "theta": 30, "delta": 0.001}
FLAGS = [f for k, v in LIMITS.items() for f in (f"--{k}", str(v))]
TOML = "\n".join(['name = "same"', 'points = "points.csv"', "[parameters]"]) + "\n"
TOML += "".join(f"{k} = {v}\n" for k, v in LIMITS.items())


def one_line_error(capsys: pytest.CaptureFixture[str], *words: str) -> str:
    err = capsys.readouterr().err.strip()
    assert err.startswith("gcs-planner: error:"), err
    assert "\n" not in err and "Traceback" not in err, err
    for word in words:
        assert word in err, err
    return err


def _not_reached(*args, **kwargs):
    raise AssertionError("the scenario was read although a flag was bad")


# --- 1. A and B in one place --------------------------------------------------------------


def _points_csv(folder: Path, b: str = "0,0,500") -> Path:
    rows = ["id,x,y,z,kind,unreliable", "A,0,0,500,A,0", "V1,9000,0,500,V,0",
            "H1,18000,0,500,H,0", f"B,{b},B,0"]  # fmt: skip
    path = folder / "points.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def _points_geojson(folder: Path) -> Path:
    def feature(pid: str, lon: float, kind: str) -> dict:
        return {
            "type": "Feature",
            "geometry": {"type": "Point", "coordinates": [lon, 30.5, 500.0]},
            "properties": {"id": pid, "kind": kind, "unreliable": 0},
        }

    doc = {"type": "FeatureCollection",
           "features": [feature("A", 123.5, "A"), feature("V1", 123.6, "V"),
                        feature("B", 123.5, "B")]}  # fmt: skip
    path = folder / "points.geojson"
    path.write_text(json.dumps(doc))
    return path


def _points_xlsx(folder: Path) -> Path:
    import openpyxl

    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["the contest's note row"])
    sheet.append(["编号", "X", "Y", "Z", "校正点类型", "第三问点标记"])
    for row in ([0, 0, 50000, 5000, "A点", 0], [1, 9000, 50000, 5000, 1, 0],
                [2, 0, 50000, 5000, "B点", 0]):  # fmt: skip
        sheet.append(row)
    path = folder / "points.xlsx"
    book.save(path)
    return path


def _scenario(folder: Path, kind: str) -> tuple[Path, Path, list[str]]:
    """(file given to plan, file the error must name, flags) with A and B in one place."""
    if kind == "toml":
        points = _points_csv(folder)
        (folder / "scenario.toml").write_text(TOML)
        return folder / "scenario.toml", points, []
    make = {"csv": _points_csv, "geojson": _points_geojson, "xlsx": _points_xlsx}[kind]
    path = make(folder)
    return path, path, FLAGS


@pytest.mark.parametrize("kind", ["csv", "toml", "geojson", "xlsx"])
def test_a_scenario_whose_a_and_b_are_one_point_is_refused(tmp_path, capsys, monkeypatch, kind):
    monkeypatch.setattr("gcs_planner.cli.plan.plan_from_args", _not_reached)
    given, named, flags = _scenario(tmp_path, kind)
    out = tmp_path / "out"
    assert main(["plan", str(given), *flags, "--out", str(out)]) == 2
    one_line_error(capsys, str(named), "A and B are the same point", "0 m mission")
    assert not out.exists()


def test_a_zero_metre_mission_is_one_line_and_no_warning_from_the_real_command(tmp_path):
    """The command as the user runs it (no pytest capture of warnings): stderr is the refusal
    alone, no matplotlib or other warning with a site-packages path."""
    given, named, _ = _scenario(tmp_path, "toml")
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "gcs_planner", "plan", str(given), "--quiet", "--out", str(out)],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )  # fmt: skip
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1, done.stderr
    assert str(named) in lines[0] and "A and B are the same point" in lines[0]
    assert done.stdout == "" and not out.exists()


def test_a_and_b_one_above_the_other_are_two_points(tmp_path):
    """The rule is one place, not one map position: B straight above A is a mission."""
    points = _points_csv(tmp_path, b="0,0,900")
    scenario = load_scenario(points, LIMITS)
    assert scenario.n == 4
    with pytest.raises(InputError, match="same point") as err:
        load_scenario(_points_csv(tmp_path), LIMITS)
    assert err.value.file == str(points) and err.value.row == 5 and err.value.field == "kind"


def test_the_front_picture_of_a_lone_zero_length_route_warns_nothing(coast_plan, tmp_path):
    """A lone route of 0 km (a plan file from before the refusal): its picture has a window,
    and matplotlib says nothing ("identical low and high ylims" before)."""
    plan = json.loads(coast_plan.read_text())
    plan["front"] = [{**plan["front"][plan["chosen"]], "length": 0.0}]
    plan["chosen"] = 0
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    out = tmp_path / "front.png"
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main(["export", str(path), "--format", "front-png", "--out", str(out)]) == 0
    assert [str(w.message) for w in caught] == []
    assert out.stat().st_size > 0


# --- 2. the front over the objectives asked for --------------------------------------------


@pytest.fixture(scope="module")
def coast_plan(tmp_path_factory) -> Path:
    """plan.json of the coast mission with the default objectives (length, corrections and
    probability: it has unreliable points), written once by `plan --out`."""
    out = tmp_path_factory.mktemp("coast") / "out"
    with pytest.MonkeyPatch.context() as patch:
        leave_pictures_undrawn(patch)  # only plan.json is read
        assert main(["plan", str(COAST), "--quiet", "--out", str(out)]) == 0
    return out / "plan.json"


def _values(route: dict) -> tuple[float, int, float]:
    return route["length"], route["corrections"], route["probability"]


def _front_over(routes: list[dict], objectives: list[str]) -> list[tuple[float, int, float]]:
    """The oracle: the values no route beats in ``objectives`` (at least as good in each,
    better in one); of ties in all of them, the shortest, then fewest corrections, then likeliest.
    """
    sense = {"length": (0, 1), "corrections": (1, 1), "probability": (2, -1)}

    def good(v, o):  # smaller is better
        i, sign = sense[o]
        return sign * v[i]

    def covers(a, b):
        return all(good(a, o) <= good(b, o) + 1e-9 for o in objectives)

    values = sorted((_values(r) for r in routes), key=lambda v: (v[0], v[1], -v[2]))
    best = [v for v in values if not any(covers(w, v) and not covers(v, w) for w in values)]
    kept: list[tuple[float, int, float]] = []
    for v in best:
        if not any(covers(w, v) for w in kept):
            kept.append(v)
    return sorted(kept, key=lambda v: (v[1], v[0]))


@pytest.mark.parametrize("objectives", ["probability", "corrections,probability"])
def test_the_front_is_over_the_objectives_asked_for(coast_plan, capsys, objectives):
    full = json.loads(coast_plan.read_text())["front"]
    names = objectives.split(",")
    want = _front_over(full, names)
    assert len(want) < len(full), "the case must have routes to leave out"
    capsys.readouterr()
    assert main(["plan", str(COAST), "--objectives", objectives, "--json", "--quiet"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["objectives"] == names
    front = [_values(r) for r in got["front"]]
    assert front == [pytest.approx(v) for v in want]
    if len(names) == 1:
        assert len(front) == 1  # one objective: one optimal route
    # No reported route is beaten in the objectives asked for by any route of the full front.
    assert _front_over(full + got["front"], names) == [pytest.approx(v) for v in front]
    assert "left out" in got["optimality"]["statement"]


# Straight legs, no unreliable point: the front over length and corrections has two routes, a
# 2-correction detour (A H2 V3 B, 47.8 km) and the 3-correction line (A V1 H1 V2 B, 46 km).
TWO_ROUTES = ["id,x,y,z,kind,unreliable", "A,0,0,500,A,0", "V1,13000,0,500,V,0",
              "H1,23000,0,500,H,0", "V2,36000,0,500,V,0", "H2,17000,6000,500,H,0",
              "V3,23000,6000,500,V,0", "B,46000,0,500,B,0"]  # fmt: skip
STRAIGHT = [*FLAGS, "--turn-radius", "0", "--origin", "30.5,123.5", "--json", "--quiet"]


@pytest.mark.parametrize(
    "objective, route",
    [("length", ["A", "V1", "H1", "V2", "B"]), ("corrections", ["A", "H2", "V3", "B"])],
)
def test_one_objective_of_two_gives_its_one_optimal_route(tmp_path, capsys, objective, route):
    points = tmp_path / "points.csv"
    points.write_text("\n".join(TWO_ROUTES) + "\n")
    assert main(["plan", str(points), *STRAIGHT, "--objectives", "length,corrections"]) == 0
    both = json.loads(capsys.readouterr().out)["front"]
    assert sorted(r["corrections"] for r in both) == [2, 3]  # the case has a route to leave out
    assert main(["plan", str(points), *STRAIGHT, "--objectives", objective]) == 0
    got = json.loads(capsys.readouterr().out)
    assert [r["route"] for r in got["front"]] == [route]
    best = min(both, key=lambda r: (r[objective], r["length"]))
    assert got["front"][0]["length"] == pytest.approx(best["length"])
    assert got["front"][0]["corrections"] == best["corrections"]


@pytest.mark.parametrize(
    "text, words",
    [
        ("", ["no objective given"]),
        (" , ", ["no objective given"]),
        ("length,length", ["length given more than once"]),
        ("length,speed", ["unknown objective", "'speed'"]),
    ],
)
def test_bad_objectives_are_refused_before_the_scenario_is_read(capsys, monkeypatch, text, words):
    monkeypatch.setattr("gcs_planner.cli.plan.load_scenario_from_args", _not_reached)
    assert main(["plan", str(COAST), "--objectives", text, "--quiet"]) == 2
    one_line_error(capsys, "--objectives", *words)


def test_a_sweep_names_an_objective_given_twice(tmp_path, capsys):
    """The sweep's [plan] objectives follow the same rule as --objectives."""
    spec = tmp_path / "sweep.toml"
    spec.write_text(f'[[scenarios]]\nfile = "{COAST}"\n[plan]\nobjectives = ["length", "length"]\n')
    out = tmp_path / "out"
    assert main(["sweep", str(spec), "--out", str(out)]) == 2
    one_line_error(capsys, str(spec), "'plan.objectives'", "'length' given more than once")
    assert not out.exists()


# --- 6. --max-corrections ----------------------------------------------------------------


def test_negative_max_corrections_is_bad_input_not_an_infeasible_plan(capsys, monkeypatch):
    monkeypatch.setattr("gcs_planner.cli.plan.load_scenario_from_args", _not_reached)
    assert main(["plan", str(COAST), "--max-corrections", "-1", "--quiet"]) == 2
    one_line_error(capsys, "--max-corrections", ">= 0", "-1")


# --- 3. a damaged plan.json ----------------------------------------------------------------


def _chosen(plan: dict) -> dict:
    return plan["front"][plan["chosen"]]


@pytest.mark.parametrize(
    "damage, field, words",
    [
        (lambda p: _chosen(p).update(length=math.nan), "front[{k}].length", ["got nan"]),
        (lambda p: _chosen(p).update(length=-5.0), "front[{k}].length", [">= 0"]),
        (lambda p: _chosen(p).update(length=None), "front[{k}].length", ["got None"]),
        (lambda p: _chosen(p).update(probability=1.7), "front[{k}].probability", ["[0, 1]"]),
        (lambda p: _chosen(p).update(probability="high"), "front[{k}].probability", ["[0, 1]"]),
        (lambda p: p["front"][0].update(corrections=-1), "front[0].corrections", [">= 0"]),
        (lambda p: _chosen(p)["legs"][0].update(v_error=math.inf), "front[{k}].legs[0].v_error",
         ["finite"]),
        (lambda p: p["parameters"].update(turn_radius=None), "parameters.turn_radius", ["None"]),
        (lambda p: p["parameters"].update(turn_radius="wide"), "parameters.turn_radius",
         ["'wide'"]),
        (lambda p: p["parameters"].update(turn_radius=math.nan), "parameters.turn_radius",
         ["nan"]),
        (lambda p: p["vehicle"].update(cruise_airspeed=None), "vehicle.cruise_airspeed",
         ["None"]),
    ],
)  # fmt: skip
@pytest.mark.parametrize("fmt", ["plan", "geojson"])
def test_a_damaged_plan_json_is_refused_naming_file_and_field(
    coast_plan, tmp_path, capsys, damage, field, words, fmt
):
    plan = json.loads(coast_plan.read_text())
    damage(plan)
    field = field.format(k=plan["chosen"])
    path = tmp_path / "damaged.json"
    path.write_text(json.dumps(plan))  # NaN and Infinity as Python's json writes them
    out = tmp_path / f"x.{fmt}"
    assert main(["export", str(path), "--format", fmt, "--out", str(out)]) == 2
    one_line_error(capsys, str(path), repr(field), *words)
    assert not out.exists()


def test_the_undamaged_plan_json_exports(coast_plan, tmp_path, capsys):
    """The checks refuse the damage, not the plan: the file as `plan` wrote it exports."""
    out = tmp_path / "x.geojson"
    assert main(["export", str(coast_plan), "--format", "geojson", "--out", str(out)]) == 0
    assert json.loads(out.read_text())["type"] == "FeatureCollection"


# --- 4. export --out ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "fmt, name, words",
    [
        ("kml", "x.plan", ["ends in .plan", "--format kml", "x.kml"]),
        ("plan", "x.KML", ["ends in .kml", "--format plan", "x.plan"]),
        ("png", "x.waypoints", ["ends in .waypoints", "x.png"]),
        ("front-png", "x.csv", ["ends in .csv", "x.png"]),
        ("geojson", "x.kml", ["ends in .kml", "x.geojson"]),
    ],
)
def test_an_out_suffix_that_contradicts_the_format_is_refused(
    coast_plan, tmp_path, capsys, fmt, name, words
):
    out = tmp_path / name
    assert main(["export", str(coast_plan), "--format", fmt, "--out", str(out)]) == 2
    one_line_error(capsys, "--out", str(out), *words)
    assert not out.exists()


@pytest.mark.parametrize("name", ["route.kml", "route", "route.xml"])
def test_an_out_suffix_of_the_format_or_of_none_is_written(coast_plan, tmp_path, capsys, name):
    out = tmp_path / name
    assert main(["export", str(coast_plan), "--format", "kml", "--out", str(out)]) == 0
    assert out.read_text().startswith("<?xml")


def test_export_creates_no_folders(coast_plan, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = Path("no/such/dir/x.plan")
    assert main(["export", str(coast_plan), "--format", "plan", "--out", str(out)]) == 2
    one_line_error(capsys, "--out", "folder no/such/dir does not exist")
    assert not (tmp_path / "no").exists()
    # A file in the way of the folder is not a folder either.
    (tmp_path / "file").write_text("keep me")
    out = tmp_path / "file" / "x.plan"
    assert main(["export", str(coast_plan), "--format", "plan", "--out", str(out)]) == 2
    one_line_error(capsys, "--out", "is not a folder")
    assert (tmp_path / "file").read_text() == "keep me"


# --- 5. the link's waits ------------------------------------------------------------------


BAD_LINK_FLAGS = [
    (["--wait", "-1"], "--wait"),
    (["--wait", "0"], "--wait"),
    (["--wait", "nan"], "--wait"),
    (["--timeout", "0"], "--timeout"),
    (["--timeout", "-2"], "--timeout"),
    (["--timeout", "inf"], "--timeout"),
    (["--retries", "-1"], "--retries"),
]


@pytest.mark.parametrize("command", ["upload", "download"])
@pytest.mark.parametrize("flags, flag", BAD_LINK_FLAGS)
def test_bad_link_waits_are_bad_input_not_a_link_failure(tmp_path, capsys, command, flags, flag):
    def no_link(*args, **kwargs):
        raise AssertionError("the link was opened although a flag was bad")

    mission = tmp_path / "m.waypoints"
    mission.write_text("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t30.5\t123.5\t10\t1\n")
    out = tmp_path / "back.json"
    what = [str(mission)] if command == "upload" else ["--out", str(out)]
    conn = ["--connect", f"udpout:127.0.0.1:{free_udp_port()}", "--quiet"]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("gcs_planner.cli.upload.open_link", no_link)
        assert main([command, *what, *conn, *flags]) == 2
    one_line_error(capsys, repr(flag), flags[1])
    assert not out.exists()


# --- 7. mock-vehicle --speedup --------------------------------------------------------------


@pytest.mark.parametrize("value", ["-1", "nan", "inf", "-inf", "fast"])
def test_a_bad_speedup_is_one_line_naming_the_flag(capsys, monkeypatch, value):
    monkeypatch.setattr("gcs_planner.cli.mock_vehicle.load_scenario_from_args", _not_reached)
    monkeypatch.setattr("gcs_planner.cli.mock_vehicle.MockVehicle", _not_reached)
    conn = f"udpin:127.0.0.1:{free_udp_port()}"
    code = main(["mock-vehicle", "--connect", conn, "--scenario", str(COAST), f"--speedup={value}"])
    assert code == 2
    one_line_error(capsys, "--speedup", repr(value))


def test_speedup_zero_is_the_documented_as_fast_as_the_link(monkeypatch):
    """--speedup 0 is documented ("0: as fast as the link takes it") and used by the dry-run
    flight test: it passes the check and reaches the scenario."""
    monkeypatch.setattr("gcs_planner.cli.mock_vehicle.load_scenario_from_args", _not_reached)
    conn = f"udpin:127.0.0.1:{free_udp_port()}"
    with pytest.raises(AssertionError, match="the scenario was read"):
        main(["mock-vehicle", "--connect", conn, "--scenario", str(COAST), "--speedup", "0"])
