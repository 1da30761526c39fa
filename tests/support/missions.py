"""A small hand-made scenario and plan dicts of its routes (docs/plan-json.md) built through the
project's own plan_json, so that the exporters are tested on the real contract; and the WGS84
position of a local point computed independently of the exporter."""

from __future__ import annotations

import math

import numpy as np
import pyproj

from gcs_planner.core.bnb import flown_route
from gcs_planner.mission import plan_json
from gcs_planner.scenario.generate import DATASET1
from gcs_planner.scenario.model import Kind, Origin, Scenario

GEOD = pyproj.Geod(ellps="WGS84")
ORIGIN = Origin(lat=31.2, lon=122.8, alt=12.5)
# Where the aircraft is armed (a deck 4 m above the sea): relative altitudes are above it.
HOME = Origin(lat=31.19, lon=122.79, alt=4.0)

# A, five correction points, B: legs of 20-40 km that turn both ways, up to ~110 km from A.
XYZ = np.array(
    [
        [0.0, 50_000.0, 5_000.0],  # A
        [22_000.0, 62_000.0, 5_600.0],  # V, left of the chord to B
        [45_000.0, 40_000.0, 4_200.0],  # H
        [60_000.0, 70_000.0, 6_100.0],  # V (unreliable)
        [80_000.0, 30_000.0, 3_900.0],  # H
        [55_000.0, 20_000.0, 4_400.0],  # V (never on the main route)
        [100_000.0, 59_000.0, 5_000.0],  # B
    ]
)
KINDS = [Kind.A, Kind.V, Kind.H, Kind.V, Kind.H, Kind.V, Kind.B]
ROUTES = ([0, 1, 2, 3, 4, 6], [0, 2, 4, 6], [0, 6])


def tiny_scenario(origin: Origin | None = ORIGIN, turn_radius: float = 200.0) -> Scenario:
    """A, five correction points (one unreliable), B, at ``origin``, dataset 1's limits."""
    return Scenario(
        ids=("A0", "11", "12", "13", "14", "15", "B9"),
        xyz=XYZ.copy(),
        kind=np.array(KINDS, dtype=np.uint8),
        unreliable=np.array([False, False, False, True, False, False, False]),
        params=DATASET1.__class__(**{**DATASET1.to_dict(), "turn_radius": turn_radius}),
        name="tiny",
        source="hand-made",
        origin=origin,
    )


def steep_scenario(firmware_limits: tuple[float, float] = (4.0, 5.0)) -> Scenario:
    """The tiny scenario with climbs that a fixed wing limited to 4/5 degrees flies on helices."""
    s = tiny_scenario()
    xyz = s.xyz.copy()
    xyz[:, 2] = [0.0, 3_500.0, 200.0, 4_000.0, 600.0, 4_400.0, 5_000.0]
    climb, descent = firmware_limits
    params = s.params.__class__(
        **{**s.params.to_dict(), "max_climb_angle": climb, "max_descent_angle": descent}
    )
    return Scenario(
        ids=s.ids, xyz=xyz, kind=s.kind, unreliable=s.unreliable, params=params,
        name="steep", source="hand-made", origin=s.origin,
    )  # fmt: skip


def make_plan(
    scenario: Scenario | None = None,
    routes: tuple[list[int], ...] = ROUTES,
    chosen: int = 0,
    probability: bool = True,
) -> dict:
    """A plan dict as `gcs-planner plan` writes it, for the given routes (front order as
    given)."""
    s = scenario if scenario is not None else tiny_scenario()
    front = []
    for points in routes:
        route = flown_route(s, tuple(points))
        p = 0.8 ** sum(bool(s.unreliable[i]) for i in points)
        route = route.with_probabilities(p, [1.0] * len(points))
        front.append(plan_json.route_to_dict(s, route, route.length))
    origin = None if s.origin is None else vars(s.origin)
    return {
        "format": "gcs-planner-plan",
        "version": 1,
        "scenario": {"name": s.name, "source": s.source, "points": s.n, "origin": origin},
        "parameters": s.params.to_dict(),
        "objectives": ["length", "corrections"] + (["probability"] if probability else []),
        "front": front,
        "chosen": chosen,
        "choice": "compromise",
        "optimality": {"optimal": False, "statement": "hand-made test routes"},
        "points": [
            {
                "id": s.ids[i],
                "x": float(s.xyz[i, 0]),
                "y": float(s.xyz[i, 1]),
                "z": float(s.xyz[i, 2]),
                "kind": Kind(int(s.kind[i])).name,
                "unreliable": bool(s.unreliable[i]),
            }
            for i in range(s.n)
        ],
    }


def true_position(origin: Origin, x: float, y: float, z: float) -> tuple[float, float, float]:
    """WGS84 position of a local point computed independently of the exporter: the geodesic from
    the origin with azimuth atan2(x, y) and length hypot(x, y) (what azimuthal equidistant
    means)."""
    lon, lat, _ = GEOD.fwd(origin.lon, origin.lat, math.degrees(math.atan2(x, y)), math.hypot(x, y))
    return lat, lon, z + origin.alt


def geodesic_distance(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Metres between two WGS84 positions along the geodesic."""
    return GEOD.inv(lon1, lat1, lon2, lat2)[2]
