"""Georeference: the local frame (metres) to WGS84 and back.

The local frame is the azimuthal equidistant projection on the WGS84 ellipsoid centred on an
origin: x east and y north in metres, z up in metres, where z = altitude AMSL minus the origin's
altitude. Azimuthal equidistant keeps distance and azimuth from the origin exact (geodesics on the
ellipsoid), so a point 100 km away lands where a surveyor would put it; a flat-earth or spherical
formula would be hundreds of metres off at that range.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from gcs_planner.errors import InputError
from gcs_planner.scenario.model import Origin

# Used (with a warning) when neither the scenario nor the command line gives an origin: open sea
# in the East China Sea, about 150 km east of Shanghai, so that a default-georeferenced mission
# never lands on a city or an airport.
DEFAULT_ORIGIN = Origin(lat=30.5, lon=123.5, alt=0.0)

DEFAULT_ORIGIN_WARNING = (
    "no origin given (scenario file or --origin LAT,LON[,ALT]): the local frame is placed at the "
    f"default origin {DEFAULT_ORIGIN.lat}, {DEFAULT_ORIGIN.lon} (open sea, East China Sea); "
    "the mission's coordinates are only meaningful relative to it"
)


def validate_origin(origin: Origin, *, file: str = "", field: str = "origin") -> Origin:
    """Return ``origin`` with float fields, or raise :class:`InputError` saying what is wrong."""

    def bad(reason: str) -> InputError:
        return InputError(reason, file=file, field=field)

    try:
        lat, lon, alt = float(origin.lat), float(origin.lon), float(origin.alt)
    except (TypeError, ValueError) as exc:
        raise bad(f"origin must be numbers (got {origin!r})") from exc
    if not math.isfinite(lat) or not -90.0 <= lat <= 90.0:
        raise bad(f"origin latitude must lie in [-90, 90] (got {lat!r})")
    if not math.isfinite(lon) or not -180.0 <= lon <= 180.0:
        raise bad(f"origin longitude must lie in [-180, 180] (got {lon!r})")
    if not math.isfinite(alt):
        raise bad(f"origin altitude must be finite (got {alt!r})")
    return Origin(lat, lon, alt)


def parse_origin(text: str, *, field: str = "--origin") -> Origin:
    """Parse ``LAT,LON[,ALT]`` (degrees, degrees, metres AMSL) as given on the command line."""
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) not in (2, 3):
        raise InputError(f"expected LAT,LON[,ALT], got {text!r}", field=field)
    try:
        values = [float(p) for p in parts]
    except ValueError as exc:
        raise InputError(f"expected numbers LAT,LON[,ALT], got {text!r}", field=field) from exc
    return validate_origin(Origin(*values), field=field)


def parse_home(text: str, *, field: str = "--home") -> Origin:
    """Parse ``LAT,LON,ALT`` (degrees, degrees, metres AMSL): all three, since relative
    altitudes are measured from ALT and a silent 0 would shift every item."""
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) != 3:
        raise InputError(f"expected LAT,LON,ALT (ALT in metres AMSL), got {text!r}", field=field)
    return parse_origin(text, field=field)


class LocalFrame:
    """The azimuthal equidistant frame on WGS84 centred on ``origin`` (see module docstring)."""

    def __init__(self, origin: Origin) -> None:
        # pyproj takes a third of a second to import: only what projects pays for it.
        from pyproj import CRS, Transformer

        self.origin = validate_origin(origin)
        o = self.origin
        local = CRS.from_proj4(
            f"+proj=aeqd +lat_0={o.lat!r} +lon_0={o.lon!r} +x_0=0 +y_0=0 "
            "+datum=WGS84 +units=m +no_defs"
        )
        # EPSG:4326 has latitude-first axis order; always_xy makes both sides (lon, lat) / (x, y).
        self._to_geo = Transformer.from_crs(local, CRS.from_epsg(4326), always_xy=True)
        self._to_xy = Transformer.from_crs(CRS.from_epsg(4326), local, always_xy=True)

    def to_geodetic(self, x: Any, y: Any, z: Any) -> tuple[Any, Any, Any]:
        """(lat, lon, alt AMSL) of local (x, y, z); scalars or numpy arrays alike."""
        lon, lat = self._to_geo.transform(np.asarray(x, float), np.asarray(y, float))
        alt = np.asarray(z, float) + self.origin.alt
        return _unwrap(lat), _unwrap(lon), _unwrap(alt)

    def to_local(self, lat: Any, lon: Any, alt: Any) -> tuple[Any, Any, Any]:
        """Local (x, y, z) of (lat, lon, alt AMSL); scalars or numpy arrays alike."""
        x, y = self._to_xy.transform(np.asarray(lon, float), np.asarray(lat, float))
        z = np.asarray(alt, float) - self.origin.alt
        return _unwrap(x), _unwrap(y), _unwrap(z)

    def __repr__(self) -> str:
        return f"LocalFrame({self.origin!r})"


def _unwrap(a: Any) -> Any:
    """Plain float for 0-d results so scalar callers get scalars back."""
    arr = np.asarray(a, float)
    return float(arr) if arr.ndim == 0 else arr
