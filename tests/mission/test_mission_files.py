"""Mission and map files: layout, round trips, atomic writes, and the export command."""

from __future__ import annotations

import csv
import io
import json
import math
import xml.etree.ElementTree as ET

import pytest
from support.missions import HOME, ORIGIN, make_plan, tiny_scenario, true_position
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.cli import main
from gcs_planner.errors import InputError
from gcs_planner.mission.builder import build_mission
from gcs_planner.mission.export import FORMATS, write_all
from gcs_planner.mission.geo_exports import csv_text, geojson_text, kml_text
from gcs_planner.mission.qgc_plan import dumps_plan, loads_plan, read_plan, write_plan
from gcs_planner.mission.waypoints import (
    dumps_items,
    dumps_waypoints,
    loads_waypoints,
    read_waypoints,
    write_waypoints,
)
from gcs_planner.scenario.model import Origin

OPTIONS = [
    {
        "firmware": fw,
        "altitude_frame": fr,
        "at_end": end,
        "home": HOME if fr == "relative" else None,
    }
    for fw in ("ardupilot", "px4")
    for fr in ("amsl", "relative")
    for end in ("loiter", "rtl", "land")
]


def option_id(opts: dict) -> str:
    return "-".join(v for v in opts.values() if isinstance(v, str))


def same_items(a, b, *, latlon_e7: int = 0, alt: float = 1e-9) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        assert (x.seq, x.frame, x.command, x.autocontinue) == (
            y.seq,
            y.frame,
            y.command,
            y.autocontinue,
        )
        for p in ("param1", "param2", "param3", "param4"):
            assert getattr(x, p) == pytest.approx(getattr(y, p), abs=1e-6)
        assert abs(x.x - y.x) <= latlon_e7 and abs(x.y - y.y) <= latlon_e7
        assert x.z == pytest.approx(y.z, abs=alt)


@pytest.mark.parametrize("opts", OPTIONS, ids=option_id)
def test_plan_round_trip(tmp_path, opts):
    m = build_mission(make_plan(), **opts)
    path = write_plan(m, tmp_path / "m.plan")
    back = read_plan(path)
    assert back.firmware == m.firmware and back.cruise_speed == m.cruise_speed
    assert back.home == pytest.approx(m.home, abs=1e-12)
    same_items(back.items, m.items)


@pytest.mark.parametrize("opts", OPTIONS, ids=option_id)
def test_waypoints_round_trip(tmp_path, opts):
    m = build_mission(make_plan(), **opts)
    if m.firmware == "px4":  # refused: readers disagree on a PX4 file's row 0 (waypoints.py)
        with pytest.raises(InputError, match="use --format plan"):
            write_waypoints(m, tmp_path / "m.waypoints")
        assert not (tmp_path / "m.waypoints").exists()
        return
    path = write_waypoints(m, tmp_path / "m.waypoints")
    back = read_waypoints(path, firmware=m.firmware)
    # 8 decimals of a degree hold degE7 exactly; altitudes carry 6 decimals.
    same_items(back.items, m.items, alt=5e-7)
    assert back.home[:2] == pytest.approx(m.home[:2], abs=0.5e-7)  # home rounded to degE7


def test_plan_layout():
    m = build_mission(make_plan(), firmware="px4", altitude_frame="relative", home=HOME)
    doc = json.loads(dumps_plan(m))
    assert doc["fileType"] == "Plan" and doc["version"] == 1 and doc["groundStation"]
    mission = doc["mission"]
    assert mission["version"] == 2 and mission["firmwareType"] == 12 and mission["vehicleType"] == 1
    assert mission["cruiseSpeed"] == 25.0 and "hoverSpeed" in mission
    assert mission["plannedHomePosition"] == pytest.approx([HOME.lat, HOME.lon, HOME.alt])
    assert doc["geoFence"] == {"version": 2, "circles": [], "polygons": []}
    assert doc["rallyPoints"] == {"version": 2, "points": []}
    items = mission["items"]
    assert len(items) == len(m.items)  # PX4: no home item to leave out
    assert [it["doJumpId"] for it in items] == list(range(1, len(items) + 1))
    for raw, item in zip(items, m.items, strict=True):
        assert raw["type"] == "SimpleItem" and len(raw["params"]) == 7
        assert raw["command"] == item.command and raw["frame"] == item.frame
        assert raw["autoContinue"] is True
        if item.frame == 3:
            assert raw["AltitudeMode"] == 1 and raw["Altitude"] == item.z
            assert raw["AMSLAltAboveTerrain"] is None
            assert raw["params"][4:] == pytest.approx([item.lat, item.lon, item.z])
    ap = json.loads(dumps_plan(build_mission(make_plan())))["mission"]
    # ArduPlane's home item left out; PX4's mission flies on beyond B (no run-out planned)
    assert ap["firmwareType"] == 3 and len(ap["items"]) == len(m.items) - 1
    assert ap["items"][1]["AltitudeMode"] == 2  # absolute


def test_waypoints_layout():
    plan = make_plan()
    for fw in ("ardupilot", "px4"):
        m = build_mission(plan, firmware=fw)
        # PX4: the layout earlier releases wrote (and download still does), still read.
        text = dumps_waypoints(m) if fw == "ardupilot" else dumps_items(m.items, fw, m.home)
        assert "\r" not in text and text.endswith("\n")
        lines = text.split("\n")[:-1]
        assert lines[0] == "QGC WPL 110"
        assert len(lines) == 1 + 1 + len(m.items) - (1 if fw == "ardupilot" else 0)
        rows = [line.split("\t") for line in lines[1:]]
        assert all(len(r) == 12 for r in rows)
        assert [int(r[0]) for r in rows] == list(range(len(rows)))
        home = rows[0]
        assert home[1] == "1" and home[3] == "16"
        assert float(home[8]) == pytest.approx(m.home[0], abs=0.5e-7)
        for r in rows:
            assert len(r[8].split(".")[1]) == 8 and len(r[9].split(".")[1]) == 8
        # Each route point's row lies on its true position (file precision 1e-8 deg).
        table = {p["id"]: p for p in plan["points"]}
        offset = 0 if fw == "ardupilot" else 1
        for pid in m.route:
            r = rows[m.seq_of(pid) + offset]
            lat, lon, alt = true_position(ORIGIN, table[pid]["x"], table[pid]["y"], table[pid]["z"])
            assert float(r[8]) == pytest.approx(lat, abs=1e-7)
            assert float(r[9]) == pytest.approx(lon, abs=1e-7)
            assert float(r[10]) == pytest.approx(alt, abs=5e-7)


@pytest.mark.parametrize(
    "text, row",
    [
        ("QGC WPL 100\n0\t1\t0\t16\t0\t0\t0\t0\t1\t2\t3\t1\n", 1),
        ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t1\t2\t3\n", 2),
        ("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\tnorth\t2\t3\t1\n", 2),
        (
            "QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t1\t2\t3\t1\n"
            "2\t0\t0\t16\t0\t0\t0\t0\t1\t2\t3\t1\n",
            3,
        ),
        ("QGC WPL 110\n", 2),
    ],
)
def test_bad_waypoints_name_the_row(text, row):
    with pytest.raises(InputError) as err:
        loads_waypoints(text, source="x.waypoints")
    assert err.value.row == row and err.value.file == "x.waypoints"


@pytest.mark.parametrize(
    "doc",
    [
        "{",
        '{"fileType": "Plan", "version": 2}',
        '{"fileType": "Plan", "version": 1, "mission": {"version": 2, "firmwareType": 99}}',
        '{"fileType": "Plan", "version": 1, "mission": {"version": 2, "firmwareType": 3,'
        ' "plannedHomePosition": [1, 2, 3], "items": [{"type": "ComplexItem"}]}}',
    ],
)
def test_bad_plan_files_are_input_errors(doc):
    with pytest.raises(InputError):
        loads_plan(doc, source="x.plan")


def test_geojson():
    plan = make_plan()
    m = build_mission(plan)
    doc = json.loads(geojson_text(plan, m))
    assert doc["type"] == "FeatureCollection"
    line, *points = doc["features"]
    assert line["geometry"]["type"] == "LineString"
    coords = line["geometry"]["coordinates"]
    assert all(len(c) == 3 for c in coords)
    # The trajectory runs from A to B, through every route point, and is as long as planned.
    assert [p["properties"]["id"] for p in points] == list(m.route)
    for p in points:
        lon, lat, alt = p["geometry"]["coordinates"]
        best = min(math.hypot((c[0] - lon) * 1e5, (c[1] - lat) * 1e5) for c in coords)
        assert best < 0.01  # a vertex of the line (units ~1 m)
        assert p["properties"]["mission_seq"] == m.seq_of(p["properties"]["id"])
    assert coords[0][:2] == pytest.approx(points[0]["geometry"]["coordinates"][:2], abs=1e-9)
    assert coords[-1][:2] == pytest.approx(points[-1]["geometry"]["coordinates"][:2], abs=1e-9)
    from pyproj import Geod

    g = Geod(ellps="WGS84")
    flat = sum(
        math.hypot(g.inv(a[0], a[1], b[0], b[1])[2], b[2] - a[2])
        for a, b in zip(coords[:-1], coords[1:], strict=True)
    )
    assert flat == pytest.approx(plan["front"][0]["length"], rel=1e-4)


def test_kml_is_well_formed_with_absolute_altitudes():
    plan = make_plan()
    m = build_mission(plan)
    root = ET.fromstring(kml_text(plan, m).encode())
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    assert root.tag == "{http://www.opengis.net/kml/2.2}kml"
    modes = [e.text for e in root.iter("{http://www.opengis.net/kml/2.2}altitudeMode")]
    assert modes and set(modes) == {"absolute"}
    line = root.find(".//k:LineString/k:coordinates", ns).text.split()
    assert len(line) > 100
    placemarks = root.findall(".//k:Folder/k:Placemark", ns)
    assert len(placemarks) == len(m.route)
    table = {p["id"]: p for p in plan["points"]}
    for pm, pid in zip(placemarks, m.route, strict=True):
        lon, lat, alt = map(float, pm.find(".//k:coordinates", ns).text.split(","))
        t_lat, t_lon, t_alt = true_position(ORIGIN, *(table[pid][c] for c in "xyz"))
        assert (lat, lon) == pytest.approx((t_lat, t_lon), abs=1e-8)
        assert alt == pytest.approx(t_alt, abs=1e-3)


def test_csv_table():
    plan = make_plan()
    m = build_mission(plan)
    rows = list(csv.DictReader(io.StringIO(csv_text(plan, m))))
    assert [r["id"] for r in rows] == list(m.route)
    legs = plan["front"][0]["legs"]
    assert rows[0]["length"] == "" and rows[0]["kind"] == "A"
    for r, leg in zip(rows[1:], legs, strict=True):
        assert float(r["cumulative"]) == pytest.approx(leg["cumulative"], abs=1e-3)
        assert float(r["v_error"]) == pytest.approx(leg["v_error"], abs=1e-6)
        assert r["kind"] == leg["kind"] and r["unreliable"] == str(int(leg["unreliable"]))
        assert int(r["mission_seq"]) == m.seq_of(r["id"])


def test_write_all_writes_every_file(tmp_path, monkeypatch):
    # The set of files is the subject: the three pictures are asked for and stood in by a
    # 1 px PNG (support/undrawn_pictures.py); what they show is test_pictures.py's, and
    # write_all draws them for real under plan --out (test_edges_files.py).
    asked = leave_pictures_undrawn(monkeypatch)
    plan = make_plan()
    paths = write_all(plan, tmp_path / "out", firmware="px4")
    assert sorted(asked) == ["error_budget_png", "front_png", "route_png"]
    names = sorted(p.name for p in paths)
    assert names == sorted(
        [
            "mission.plan",  # PX4: no mission.waypoints (readers disagree on its row 0)
            "route.geojson",
            "route.kml",
            "route.csv",
            "route.png",
            "front.png",
            "error_budget.png",
        ]  # fmt: skip
    )
    assert all(p.stat().st_size > 0 for p in paths)
    assert read_plan(tmp_path / "out" / "mission.plan").firmware == "px4"
    assert sorted(f.name for f in (tmp_path / "out").iterdir()) == names  # no temp files left


def test_write_all_leaves_the_folder_alone_on_bad_input(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "mission.plan").write_text("old")
    with pytest.raises(InputError):
        write_all(make_plan(), out, acceptance_radius=2.5)
    with pytest.raises(InputError):
        write_all({"format": "nope"}, out)
    assert [f.name for f in out.iterdir()] == ["mission.plan"]
    assert (out / "mission.plan").read_text() == "old"


# ---------------------------------------------------------------------------------------------
# gcs-planner export


@pytest.fixture
def plan_file(tmp_path):
    """A plan whose chosen route (P 0.8) was chosen with --min-probability 0."""
    path = tmp_path / "plan.json"
    path.write_text(json.dumps({**make_plan(), "min_probability": 0.0}))
    return path


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_export_command_writes_each_format(plan_file, tmp_path, fmt, capsys):
    out = tmp_path / f"x.{fmt}"
    assert main(["export", str(plan_file), "--format", fmt, "--out", str(out)]) == 0
    assert out.stat().st_size > 0
    err = capsys.readouterr().err
    assert "origin" not in err  # the plan has one
    # The chosen route arrives with P 0.8: exported (the plan asked for no more), with a warning.
    assert "warning: route 0 arrives with probability 0.8000" in err


def test_export_command_options(plan_file, tmp_path):
    out = tmp_path / "m.plan"
    args = ["export", str(plan_file), "--format", "plan", "--out", str(out),
            "--autopilot", "px4", "--altitude-frame", "relative", "--capture-radius", "30",
            "--cruise-speed", "31", "--at-end", "rtl", "--route-index", "1",
            "--origin", "10,20,5", "--home", "10.01,20.01,2"]  # fmt: skip
    assert main(args) == 0
    expected = build_mission(
        make_plan(), firmware="px4", altitude_frame="relative", acceptance_radius=30,
        cruise_speed=31, at_end="rtl", route_index=1, origin=Origin(10, 20, 5),
        home=Origin(10.01, 20.01, 2),
    )  # fmt: skip
    back = read_plan(out)
    assert back.firmware == "px4" and back.home == pytest.approx((10.01, 20.01, 2))
    same_items(back.items, expected.items, alt=5e-7)


def test_export_warns_about_the_default_origin(tmp_path, capsys):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(make_plan(tiny_scenario(origin=None))))
    out = str(tmp_path / "r.kml")
    assert main(["export", str(path), "--format", "kml", "--out", out, "--allow-risky"]) == 0
    assert "default origin" in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra, content",
    [
        (["--origin", "91,0"], None),
        (["--origin", "nan,0"], None),
        (["--origin", "north"], None),
        (["--capture-radius", "7.5"], None),
        (["--route-index", "9"], None),
        ([], "{not json"),
        ([], '{"format": "something-else"}'),
    ],
)
def test_export_bad_input_exits_2_without_traceback(plan_file, tmp_path, capsys, extra, content):
    if content is not None:
        plan_file.write_text(content)
    out = tmp_path / "x.plan"
    code = main(["export", str(plan_file), "--format", "plan", "--out", str(out), *extra])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("gcs-planner: error:") and "Traceback" not in err
    assert not out.exists()
