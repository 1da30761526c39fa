"""Landmarks in latitude, longitude and altitude: read (CSV and GeoJSON), projected with the
exporter's own frame, planned, exported, and every correction waypoint back on its landmark."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from pyproj import Geod
from support.paths import MISSIONS

from gcs_planner import load_scenario, plan, write_mission
from gcs_planner.cli import main
from gcs_planner.mission.builder import build_mission
from gcs_planner.mission.plan_json import plan_to_dict
from gcs_planner.mission.qgc_plan import read_plan
from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.scenario.model import Kind, Origin

EXAMPLE = MISSIONS / "example"
LIMITS = dict(alpha1=25, alpha2=15, beta1=20, beta2=25, theta=30, delta=0.001)
WGS84 = Geod(ellps="WGS84")
# A survey somewhere else than the exporter's default origin, with an altitude datum of its own.
SURVEY_ORIGIN = Origin(43.2, 5.3, 0.0)


def landmarks(n: int = 40, seed: int = 3) -> list[dict]:
    """A geographic scenario: A, B and n correction points over 50 x 12 km of sea, ids that
    are not row numbers."""
    rng = np.random.default_rng(seed)
    frame = LocalFrame(SURVEY_ORIGIN)
    xyz = np.column_stack(
        [rng.uniform(0, 50_000, n), rng.uniform(-6_000, 6_000, n), rng.uniform(300, 2_000, n)]
    )
    xyz = np.vstack([[0.0, 0.0, 800.0], xyz, [50_000.0, 0.0, 1_200.0]])
    lat, lon, alt = frame.to_geodetic(xyz[:, 0], xyz[:, 1], xyz[:, 2])
    rows = []
    for i in range(n + 2):
        kind = "A" if i == 0 else "B" if i == n + 1 else ("V" if i % 2 else "H")
        rows.append(
            {
                "id": f"LM-{i:03d}",
                "lat": float(lat[i]),
                "lon": float(lon[i]),
                "alt": float(alt[i]),
                "kind": kind,
                "unreliable": int(kind in "VH" and i % 7 == 3),
            }
        )
    return rows


def write_csv(path: Path, rows: list[dict]) -> Path:
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, ["id", "lat", "lon", "alt", "kind", "unreliable"])
        w.writeheader()
        for r in rows:
            w.writerow({**r, "lat": repr(r["lat"]), "lon": repr(r["lon"]), "alt": repr(r["alt"])})
    return path


def write_geojson(path: Path, rows: list[dict]) -> Path:
    features = [
        {
            "type": "Feature",
            "geometry": {"type": "Point", "coordinates": [r["lon"], r["lat"], r["alt"]]},
            "properties": {"id": r["id"], "kind": r["kind"], "unreliable": bool(r["unreliable"])},
        }
        for r in rows
    ]
    path.write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    return path


def assert_waypoints_on_landmarks(result, mission_file: Path, rows: list[dict]) -> int:
    """Every point of the chosen route has its waypoint within 5 cm (3D) of its landmark."""
    by_id = {r["id"]: r for r in rows}
    seqs = dict(build_mission(plan_to_dict(result)).point_seqs)
    items = {item.seq: item for item in read_plan(mission_file).items}
    checked = 0
    for pid in result.route.ids():
        item, mark = items[seqs[pid]], by_id[pid]
        _, _, across = WGS84.inv(mark["lon"], mark["lat"], item.lon, item.lat)
        assert np.hypot(across, item.z - mark["alt"]) < 0.05, pid
        checked += 1
    return checked


@pytest.mark.parametrize("fmt", ["csv", "geojson"])
def test_geographic_landmarks_round_trip_to_the_mission(tmp_path, fmt):
    rows = landmarks()
    write = write_csv if fmt == "csv" else write_geojson
    path = write(tmp_path / f"landmarks.{fmt}", rows)
    scenario = load_scenario(path, **LIMITS, turn_radius=200)
    # Without an origin the frame sits on A at mean sea level: z is the altitude AMSL.
    assert scenario.origin == Origin(rows[0]["lat"], rows[0]["lon"], 0.0)
    assert scenario.xyz[scenario.start] == pytest.approx([0.0, 0.0, rows[0]["alt"]], abs=1e-6)
    result = plan(scenario, min_probability=0.0)
    assert set(result.route.ids()) <= {r["id"] for r in rows}  # reported in the file's ids
    out = write_mission(result, tmp_path / "mission.plan", allow_risky=True)
    assert assert_waypoints_on_landmarks(result, out, rows) >= 3


def test_a_toml_origin_is_the_frame_and_plans_the_same_routes(tmp_path):
    rows = landmarks()
    write_csv(tmp_path / "landmarks.csv", rows)
    toml = tmp_path / "survey.toml"
    toml.write_text(
        'points = "landmarks.csv"\n[parameters]\n'
        + "".join(f"{k} = {v}\n" for k, v in LIMITS.items())
        + "turn_radius = 200\n"
        + f"[origin]\nlat = {SURVEY_ORIGIN.lat}\nlon = {SURVEY_ORIGIN.lon}\n"
    )
    in_survey_frame = load_scenario(toml)
    on_a = load_scenario(tmp_path / "landmarks.csv", **LIMITS, turn_radius=200)
    # The landmarks were made in the survey frame: projected back, they are where they were.
    assert in_survey_frame.xyz[in_survey_frame.start] == pytest.approx([0, 0, 800], abs=1e-6)
    assert in_survey_frame.xyz[-1] == pytest.approx([50_000, 0, 1_200], abs=1e-6)
    a, b = plan(in_survey_frame), plan(on_a)
    assert [r.ids() for r in a.front] == [r.ids() for r in b.front]
    assert [r.length for r in a.front] == pytest.approx([r.length for r in b.front], abs=1.0)
    out = write_mission(a, tmp_path / "mission.plan", allow_risky=True)
    assert_waypoints_on_landmarks(a, out, rows)


def test_geographic_csv_plans_from_the_command_line(tmp_path, capsys):
    path = write_csv(tmp_path / "landmarks.csv", landmarks())
    flags = [f"--{k}={v}" for k, v in LIMITS.items()]
    assert main(["plan", str(path), *flags, "--min-probability", "0", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["scenario"]["origin"]["alt"] == 0.0
    assert data["front"][data["chosen"]]["route"][0] == "LM-000"
    kinds = {p["id"]: p["kind"] for p in data["points"]}
    assert kinds["LM-000"] == Kind.A.name


@pytest.mark.parametrize(
    "change, field",
    [
        ({"lat": 95.0}, "lat"),
        ({"lon": -181.0}, "lon"),
        ({"alt": "high"}, "alt"),
        ({"lat": ""}, "lat"),
    ],
)
def test_bad_geographic_csv_names_row_and_column(tmp_path, capsys, change, field):
    rows = landmarks(6)
    rows[2] = {**rows[2], **change}
    path = tmp_path / "bad.csv"
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, ["id", "lat", "lon", "alt", "kind", "unreliable"])
        w.writeheader()
        w.writerows(rows)
    flags = [f"--{k}={v}" for k, v in LIMITS.items()]
    assert main(["plan", str(path), *flags]) == 2
    err = capsys.readouterr().err
    assert f"row 4, field '{field}'" in err and "Traceback" not in err


@pytest.mark.parametrize(
    "mangle, words",
    [
        (lambda d: d["features"][1]["geometry"].update(coordinates=[5.3, 43.2]), "altitude"),
        (lambda d: d["features"][1]["properties"].pop("unreliable"), "properties.unreliable"),
        (lambda d: d["features"][1]["geometry"].update(type="LineString"), "Point"),
        (lambda d: d.update(type="Feature"), "FeatureCollection"),
    ],
)
def test_bad_geojson_names_the_feature(tmp_path, capsys, mangle, words):
    path = write_geojson(tmp_path / "bad.geojson", landmarks(6))
    doc = json.loads(path.read_text())
    mangle(doc)
    path.write_text(json.dumps(doc))
    flags = [f"--{k}={v}" for k, v in LIMITS.items()]
    assert main(["plan", str(path), *flags]) == 2
    err = capsys.readouterr().err
    assert words in err and err.startswith("gcs-planner: error:") and "Traceback" not in err
