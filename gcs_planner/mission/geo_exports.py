"""The chosen route for map tools: GeoJSON, KML (absolute altitudes, opens in Google Earth) and
the per-point table as CSV.

The flown trajectory is sampled from the plan's leg geometry (arcs and straights), not from the
mission's waypoints, so the maps show what was planned; the route's points carry the numbers of
the route table and the seq of their waypoint in the mission.
"""

from __future__ import annotations

import csv
import io
import json
import math
import xml.etree.ElementTree as ET
from typing import Any

import numpy as np

from gcs_planner.mission.builder import Mission, point_table, route_entry, route_legs, route_xyz
from gcs_planner.scenario.georef import LocalFrame

# Spacing of the trajectory's samples: fine enough that a 200 m turn looks round on a map.
TRAJECTORY_STEP_M = 20.0
KML_NS = "http://www.opengis.net/kml/2.2"


def trajectory_local(plan: dict, route_index: int | None = None, step: float = TRAJECTORY_STEP_M):
    """(k, 3) local polyline of the route's flown path, A to B, samples at most ``step`` apart."""
    _, entry = route_entry(plan, route_index)
    legs = route_legs(entry)
    parts = [legs[0].sample(step)] + [leg.sample(step)[1:] for leg in legs[1:]]
    return np.concatenate(parts, axis=0)


def route_points(plan: dict, mission: Mission) -> list[dict[str, Any]]:
    """One row per point of the mission's route: ids, local and WGS84 positions, the plan's leg
    numbers on arrival, and the seq of the point's waypoint."""
    _, entry = route_entry(plan, mission.route_index)
    legs = route_legs(entry)
    xyz = route_xyz(plan, entry, legs)
    table = point_table(plan)
    frame = LocalFrame(mission.origin)
    lat, lon, alt = frame.to_geodetic(xyz[:, 0], xyz[:, 1], xyz[:, 2])
    rows = []
    for k, pid in enumerate(entry["route"]):
        pid = str(pid)
        leg = entry["legs"][k - 1] if k > 0 else {}
        kind = leg.get("kind") or table.get(pid, {}).get("kind") or ("A" if k == 0 else "")
        rows.append(
            {
                "order": k,
                "id": pid,
                "kind": kind,
                "unreliable": bool(leg.get("unreliable", table.get(pid, {}).get("unreliable"))),
                "x": float(xyz[k, 0]),
                "y": float(xyz[k, 1]),
                "z": float(xyz[k, 2]),
                "lat": float(lat[k]),
                "lon": float(lon[k]),
                "alt_amsl": float(alt[k]),
                "mission_seq": mission.point_seqs[k][1],
                **{f: leg.get(f) for f in LEG_FIELDS},
            }
        )
    return rows


LEG_FIELDS = (
    "length",
    "arc",
    "straight",
    "turn_angle_deg",
    "cumulative",
    "v_error",
    "h_error",
    "v_limit",
    "h_limit",
    "v_margin",
    "h_margin",
    "p_arrive",
)


def _summary(plan: dict, mission: Mission) -> dict[str, Any]:
    _, entry = route_entry(plan, mission.route_index)
    return {
        "route_index": mission.route_index,
        "length_m": float(entry.get("length", math.nan)),
        "corrections": entry.get("corrections"),
        "probability": entry.get("probability"),
        "turn_radius_m": mission.turn_radius,
        "origin": {"lat": mission.origin.lat, "lon": mission.origin.lon, "alt": mission.origin.alt},
        "origin_is_default": mission.origin_is_default,
    }


def _geodetic_track(plan: dict, mission: Mission) -> np.ndarray:
    """(k, 3) lon, lat, alt AMSL of the flown trajectory."""
    t = trajectory_local(plan, mission.route_index)
    lat, lon, alt = LocalFrame(mission.origin).to_geodetic(t[:, 0], t[:, 1], t[:, 2])
    return np.column_stack([lon, lat, alt])


def _clean(value: Any) -> Any:
    """JSON has no inf/NaN: limits and margins at A are infinite, written as null."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def geojson_text(plan: dict, mission: Mission) -> str:
    """RFC 7946 FeatureCollection: the flown trajectory (LineString, altitude AMSL as the third
    coordinate) and the route's points (Point features with the table's numbers)."""
    track = _geodetic_track(plan, mission)
    features = [
        {
            "type": "Feature",
            "geometry": {
                "type": "LineString",
                "coordinates": [[round(v, 9) for v in p[:2]] + [round(p[2], 3)] for p in track],
            },
            "properties": {"name": "flown trajectory", **_summary(plan, mission)},
        }
    ]
    for row in route_points(plan, mission):
        props = {k: _clean(v) for k, v in row.items() if k not in ("lat", "lon")}
        features.append(
            {
                "type": "Feature",
                "geometry": {
                    "type": "Point",
                    "coordinates": [row["lon"], row["lat"], row["alt_amsl"]],
                },
                "properties": props,
            }
        )
    doc = {"type": "FeatureCollection", "features": features}
    return json.dumps(doc, separators=(",", ":"), allow_nan=False) + "\n"


# ---------------------------------------------------------------------------------------------
# KML

_STYLES = {  # KML colours are aabbggrr
    "track": ("ff0000ff", None),
    "A": (None, "ff00aa00"),
    "B": (None, "ff0000cc"),
    "V": (None, "ffcc6600"),
    "H": (None, "ff0088ff"),
}


def _sub(parent: ET.Element, tag: str, text: str | None = None) -> ET.Element:
    el = ET.SubElement(parent, f"{{{KML_NS}}}{tag}")
    if text is not None:
        el.text = text
    return el


def _coord(lon: float, lat: float, alt: float) -> str:
    return f"{lon:.9f},{lat:.9f},{alt:.3f}"


def kml_text(plan: dict, mission: Mission) -> str:
    """KML 2.2 document: the trajectory as a LineString and the route's points as Placemarks,
    all with altitudeMode absolute (metres above mean sea level)."""
    ET.register_namespace("", KML_NS)
    root = ET.Element(f"{{{KML_NS}}}kml")
    doc = _sub(root, "Document")
    s = _summary(plan, mission)
    _sub(doc, "name", f"gcs-planner route {s['route_index']}")
    _sub(
        doc,
        "description",
        f"{s['corrections']} corrections, {s['length_m']:.1f} m flown; "
        f"origin {mission.origin.lat}, {mission.origin.lon}"
        + (" (default origin)" if mission.origin_is_default else ""),
    )
    for name, (line, icon) in _STYLES.items():
        style = _sub(doc, "Style")
        style.set("id", name)
        if line:
            ls = _sub(style, "LineStyle")
            _sub(ls, "color", line)
            _sub(ls, "width", "3")
        if icon:
            ic = _sub(style, "IconStyle")
            _sub(ic, "color", icon)
            _sub(ic, "scale", "1.2" if name in ("A", "B") else "0.9")

    pm = _sub(doc, "Placemark")
    _sub(pm, "name", "flown trajectory")
    _sub(pm, "styleUrl", "#track")
    ls = _sub(pm, "LineString")
    _sub(ls, "altitudeMode", "absolute")
    track = _geodetic_track(plan, mission)
    _sub(ls, "coordinates", " ".join(_coord(*p) for p in track))

    folder = _sub(doc, "Folder")
    _sub(folder, "name", "route points")
    for row in route_points(plan, mission):
        pm = _sub(folder, "Placemark")
        flag = " (unreliable)" if row["unreliable"] else ""
        _sub(pm, "name", f"{row['order']}: {row['id']} {row['kind']}{flag}")
        lines = [f"altitude {row['alt_amsl']:.1f} m AMSL", f"mission seq {row['mission_seq']}"]
        if row["cumulative"] is not None:
            lines.append(f"flown {row['cumulative']:.1f} m")
            lines.append(f"errors on arrival v {row['v_error']:.3f}, h {row['h_error']:.3f}")
        _sub(pm, "description", "; ".join(lines))
        _sub(pm, "styleUrl", f"#{row['kind'] if row['kind'] in _STYLES else 'V'}")
        pt = _sub(pm, "Point")
        _sub(pt, "altitudeMode", "absolute")
        _sub(pt, "coordinates", _coord(row["lon"], row["lat"], row["alt_amsl"]))
    ET.indent(root, space=" ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


# ---------------------------------------------------------------------------------------------
# CSV

CSV_COLUMNS = (
    "order",
    "id",
    "kind",
    "unreliable",
    "mission_seq",
    "x",
    "y",
    "z",
    "lat",
    "lon",
    "alt_amsl",
    *LEG_FIELDS,
)


def _cell(name: str, value: Any) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return ""
    if isinstance(value, bool):
        return str(int(value))
    if name in ("lat", "lon"):
        return f"{value:.9f}"
    if isinstance(value, float):
        return (
            f"{value:.6f}"
            if name in ("v_error", "h_error", "v_margin", "h_margin")
            else f"{value:.3f}"
        )
    return str(value)


def csv_text(plan: dict, mission: Mission) -> str:
    """The route's per-point table: position (local and WGS84), the leg flown to reach the point,
    the errors on arrival and their margins, and the point's mission seq."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for row in route_points(plan, mission):
        w.writerow([_cell(c, row[c]) for c in CSV_COLUMNS])
    return buf.getvalue()
