"""The dry run's flown track beside the mission's path, as GeoJSON or KML (``--track-out``).

LineStrings in WGS84 (longitude, latitude, metres above mean sea level): the planned path (the
plan's legs, helices included), the stored mission's path (its items joined by straight chords)
and the track the mock vehicle flew to B, plus one
Point per correction landmark of the route, saying whether the flight corrected there or missed
it and by how much (3D closest approach).
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from gcs_planner.runtime.atomic import write_atomic
from gcs_planner.scenario.model import Scenario
from gcs_planner.sim import replay as replay_mod


def _geodetic(frame: Any, points: np.ndarray) -> list[list[float]]:
    lat, lon, alt = frame.to_geodetic(points[:, 0], points[:, 1], points[:, 2])
    return [
        [round(float(a), 7), round(float(b), 7), round(float(c), 2)]
        for a, b, c in zip(np.atleast_1d(lon), np.atleast_1d(lat), np.atleast_1d(alt), strict=True)
    ]


def track_features(
    report: replay_mod.ReplayReport,
    scenario: Scenario,
    route: Sequence[str],
    planned: np.ndarray | None = None,
) -> list[dict[str, Any]]:
    """GeoJSON features: planned path, mission path, flown track, route landmarks with their
    outcome."""
    frame = replay_mod.scenario_frame(scenario)
    feats: list[dict[str, Any]] = []
    if planned is not None and len(planned) > 1:
        length = float(np.linalg.norm(np.diff(planned, axis=0), axis=1).sum())
        feats.append(_line("planned path", _geodetic(frame, planned), length))
    assert report.nominal is not None and report.flown is not None
    nominal = _geodetic(frame, report.nominal.points)
    feats.append(_line("mission path", nominal, report.mission_length))
    feats.append(_line("flown track", _geodetic(frame, report.flown.points), report.flown.length))
    met = {e.id: e for e in report.encounters}
    missed = {m.id: m for m in report.missed}
    for pid in route[1:-1]:
        i = scenario.index_of(pid)
        (coords,) = _geodetic(frame, scenario.xyz[i][None, :])
        if pid in met:
            status, miss = "corrected", met[pid].miss
        elif pid in missed:
            status, miss = "missed", missed[pid].miss
        else:
            status, miss = "not reached", None
        feats.append(
            {
                "type": "Feature",
                "geometry": {"type": "Point", "coordinates": coords},
                "properties": {"name": str(pid), "status": status, "miss_m": miss},
            }
        )
    return feats


def _line(name: str, coords: list[list[float]], length: float) -> dict[str, Any]:
    return {
        "type": "Feature",
        "geometry": {"type": "LineString", "coordinates": coords},
        "properties": {"name": name, "length_m": round(float(length), 2)},
    }


def geojson_text(
    report: replay_mod.ReplayReport,
    scenario: Scenario,
    route: Sequence[str],
    planned: np.ndarray | None = None,
) -> str:
    feats = track_features(report, scenario, route, planned)
    collection = {"type": "FeatureCollection", "features": feats}
    return json.dumps(collection, indent=1) + "\n"


def kml_text(
    report: replay_mod.ReplayReport,
    scenario: Scenario,
    route: Sequence[str],
    planned: np.ndarray | None = None,
) -> str:
    kml = ET.Element("kml", xmlns="http://www.opengis.net/kml/2.2")
    doc = ET.SubElement(kml, "Document")
    ET.SubElement(doc, "name").text = f"dry run of {scenario.name}"
    for feat in track_features(report, scenario, route, planned):
        mark = ET.SubElement(doc, "Placemark")
        props = feat["properties"]
        ET.SubElement(mark, "name").text = props["name"]
        if "status" in props:
            miss = props["miss_m"]
            extra = "" if miss is None else f", closest {miss:.1f} m"
            ET.SubElement(mark, "description").text = props["status"] + extra
        geom = feat["geometry"]
        coords = geom["coordinates"]
        if geom["type"] == "Point":
            el = ET.SubElement(mark, "Point")
            coords = [coords]
        else:
            el = ET.SubElement(mark, "LineString")
            ET.SubElement(el, "tessellate").text = "1"
        ET.SubElement(el, "altitudeMode").text = "absolute"
        ET.SubElement(el, "coordinates").text = " ".join(f"{a},{b},{c}" for a, b, c in coords)
    return ET.tostring(kml, encoding="unicode", xml_declaration=True) + "\n"


def write_track(
    path: str,
    report: replay_mod.ReplayReport,
    scenario: Scenario,
    route: Sequence[str],
    planned: np.ndarray | None = None,
) -> Path:
    """Write the track file, KML for a .kml name, GeoJSON otherwise (atomically)."""
    if path.lower().endswith(".kml"):
        return write_atomic(path, kml_text(report, scenario, route, planned))
    return write_atomic(path, geojson_text(report, scenario, route, planned))
