"""Layout of a GeoJSON points file: a FeatureCollection of Point features, coordinates
[longitude, latitude, altitude above mean sea level] (RFC 7946 order), ``properties`` carrying
``id``, ``kind`` and ``unreliable``. Meaning is checked in readers, as for the other formats.

In error messages the row is the feature's number in the collection, counting from 1.
"""

from __future__ import annotations

import json
from pathlib import Path

from gcs_planner.errors import InputError
from gcs_planner.scenario.geographic import CellTable

LABELS = {
    "id": "properties.id",
    "lat": "coordinates[1] (latitude)",
    "lon": "coordinates[0] (longitude)",
    "alt": "coordinates[2] (altitude)",
    "kind": "properties.kind",
    "unreliable": "properties.unreliable",
}


def read_geojson_cells(path: Path) -> CellTable:
    """Header 0, and each feature as (its number, cells by column)."""
    file = str(path)
    try:
        doc = json.loads(path.read_bytes().decode("utf-8-sig"))
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", file=file) from None
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text (offset {exc.start})", file=file) from None
    except json.JSONDecodeError as exc:
        raise InputError(f"not JSON: {exc.msg} (line {exc.lineno})", file=file) from None
    if not isinstance(doc, dict) or doc.get("type") != "FeatureCollection":
        raise InputError('expected a GeoJSON "FeatureCollection"', file=file, field="type")
    features = doc.get("features")
    if not isinstance(features, list) or not features:
        raise InputError(
            "no features: one Point per landmark, A and B", file=file, field="features"
        )
    rows: list[tuple[int, dict[str, object]]] = []
    for n, feature in enumerate(features, start=1):

        def fail(message: str, field: str, n: int = n) -> InputError:
            return InputError(message, file=file, row=n, field=field)

        if not isinstance(feature, dict) or feature.get("type") != "Feature":
            raise fail('expected a "Feature"', "type")
        geometry = feature.get("geometry")
        if not isinstance(geometry, dict) or geometry.get("type") != "Point":
            raise fail("expected a Point geometry (one landmark per feature)", "geometry.type")
        coords = geometry.get("coordinates")
        if not isinstance(coords, list) or len(coords) != 3:
            raise fail(
                "expected [longitude, latitude, altitude]: the altitude above mean sea level is "
                "needed",
                "geometry.coordinates",
            )
        props = feature.get("properties")
        if not isinstance(props, dict):
            raise fail("expected an object with id, kind and unreliable", "properties")
        # unreliable too: a misspelt flag must not make a point silently reliable.
        missing = [k for k in ("id", "kind", "unreliable") if k not in props]
        if missing:
            raise fail(f"missing {', '.join(missing)}", f"properties.{missing[0]}")
        cells = {
            "id": props["id"],
            "lon": coords[0],
            "lat": coords[1],
            "alt": coords[2],
            "kind": props["kind"],
            "unreliable": props["unreliable"],
        }
        rows.append((n, cells))
    return 0, rows, dict(LABELS)
