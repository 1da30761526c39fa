"""The dry run's flight in its report and files: the flown track beside the mission's path
(GeoJSON, KML), the acceptance radius flag, and bad values of both."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from support.dry_run_line import LINE_FLAGS, write_line

from gcs_planner.cli import main


@pytest.fixture(scope="module")
def line_csv(tmp_path_factory) -> Path:
    return write_line(tmp_path_factory.mktemp("line"))


def run(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(["dry-run", *argv])
    out, err = capsys.readouterr()
    return rc, out, err


def test_flown_track_is_written_as_geojson_beside_the_mission_path(capsys, tmp_path, line_csv):
    dest = tmp_path / "track.geojson"
    rc, out, _ = run(capsys, str(line_csv), *LINE_FLAGS, "--track-out", str(dest), "--json")
    d = json.loads(out)
    feats = json.loads(dest.read_text())["features"]
    lines = {f["properties"]["name"]: f for f in feats if f["geometry"]["type"] == "LineString"}
    assert set(lines) == {"planned path", "mission path", "flown track"}
    flown = lines["flown track"]
    assert flown["properties"]["length_m"] == pytest.approx(d["flown_to_b"], abs=0.01)
    assert len(flown["geometry"]["coordinates"]) > len(
        lines["mission path"]["geometry"]["coordinates"]
    )
    points = [f for f in feats if f["geometry"]["type"] == "Point"]
    assert [p["properties"]["name"] for p in points] == d["route"][1:-1]
    assert all(p["properties"]["status"] in ("corrected", "missed", "not reached") for p in points)
    for c in flown["geometry"]["coordinates"]:
        assert -180 <= c[0] <= 180 and -90 <= c[1] <= 90


def test_flown_track_as_kml(capsys, tmp_path, line_csv):
    dest = tmp_path / "track.kml"
    run(capsys, str(line_csv), *LINE_FLAGS, "--track-out", str(dest))
    root = ET.fromstring(dest.read_text())
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    names = [n.text for n in root.iterfind(".//k:Placemark/k:name", ns)]
    assert names[:3] == ["planned path", "mission path", "flown track"]


def test_the_report_names_the_acceptance_and_capture_radii(capsys, line_csv):
    rc, out, _ = run(capsys, str(line_csv), *LINE_FLAGS, "--acceptance-radius", "3")
    assert "acceptance radius 3 m, capture radius 5 m" in out
    assert "largest deviation" in out


@pytest.mark.parametrize(
    "argv, field",
    [
        (["--acceptance-radius", "0"], "--acceptance-radius"),
        (["--acceptance-radius", "300"], "--acceptance-radius"),
        (["--acceptance-radius", "x"], "--acceptance-radius"),
        (["--track-out", "track.txt"], "--track-out"),
        (["--track-out", "__file__/x.geojson"], "--track-out"),
    ],
)
def test_bad_flight_flags_are_one_line_and_exit_2(capsys, tmp_path, line_csv, argv, field):
    blocker = tmp_path / "__file__"
    blocker.write_text("")  # a file where the track's folder would be
    argv = [a.replace("__file__", str(blocker)) for a in argv]
    rc, out, err = run(capsys, str(line_csv), *LINE_FLAGS, *argv)
    assert rc == 2 and field in err and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err
