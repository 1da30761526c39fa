"""The flown path of a whole route: one CS leg per hop, each starting with the heading the previous
one ended with (MODEL.md, "Leg geometry"), and its JSON-ready form for the exporters.

Pure numpy, no I/O. A route whose Dubins form has a target inside a turning circle still gives a
``Trajectory`` (its length is inf and ``reachable`` is False) so that the caller can say which leg
fails; it has no polyline.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs_planner.geometry.dubins import COINCIDENT_M, CSLeg, cs_leg, straight_leg


@dataclass(frozen=True, eq=False)
class Trajectory:
    """The legs of a route, A first."""

    legs: tuple[CSLeg, ...]

    @property
    def length(self) -> float:
        return math.fsum(leg.length for leg in self.legs)

    @property
    def reachable(self) -> bool:
        return all(leg.reachable for leg in self.legs)

    def polyline(self, max_step: float = 50.0) -> np.ndarray:
        """(k, 3) dense polyline of the whole route, consecutive points at most ``max_step``
        apart; the route's points and the tangent points are vertices."""
        if not self.reachable:
            bad = next(k for k, leg in enumerate(self.legs) if not leg.reachable)
            raise ValueError(f"leg {bad} is not flyable: its target lies inside the turning circle")
        parts = [self.legs[0].sample(max_step)]
        parts += [leg.sample(max_step)[1:] for leg in self.legs[1:]]
        return np.concatenate(parts, axis=0)

    def headings(self) -> list[np.ndarray]:
        """Unit heading at each point of the route, A first."""
        return [self.legs[0].heading_in.copy()] + [leg.heading_out.copy() for leg in self.legs]


def route_trajectory(
    xyz: np.ndarray, radius: float, heading_at_a: np.ndarray | None = None
) -> Trajectory:
    """The trajectory through the points ``xyz`` (m, 3), A..B, with turning radius ``radius``.

    With ``heading_at_a`` None the heading at A is free and the first leg is the straight chord
    (heading at A = direction to the first target). Otherwise the first leg is a CS leg from it.
    """
    pts = np.asarray(xyz, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2:
        raise ValueError(f"a route needs at least two 3D points (m, 3), got shape {pts.shape}")
    if heading_at_a is None:
        first = straight_leg(pts[0], pts[1], _first_direction(pts), radius)
    else:
        first = cs_leg(pts[0], heading_at_a, pts[1], radius)
    legs = [first]
    for k in range(1, pts.shape[0] - 1):
        prev = legs[-1]
        if not prev.reachable:  # no heading to carry on with; the rest cannot be flown either
            heading = prev.heading_in
        else:
            heading = prev.heading_out
        legs.append(cs_leg(pts[k], heading, pts[k + 1], radius))
    return Trajectory(legs=tuple(legs))


def _first_direction(pts: np.ndarray) -> np.ndarray:
    """Heading at A when it is free and A coincides with the next point: the first chord that
    is not zero (longer than COINCIDENT_M), else east."""
    for k in range(1, pts.shape[0]):
        w = pts[k] - pts[0]
        norm = math.sqrt(float(w @ w))
        if norm > COINCIDENT_M:
            return w / norm
    return np.array([1.0, 0.0, 0.0])


def _frozen(v: np.ndarray) -> np.ndarray:
    v = np.array(v, dtype=float)
    v.setflags(write=False)
    return v


def _vec(v: np.ndarray) -> list[float]:
    return [float(x) for x in v]


def leg_to_dict(leg: CSLeg) -> dict:
    """The leg as plain JSON-ready data (lists of floats). An unreachable leg has no flight path
    and raises ``ValueError``."""
    if not leg.reachable:
        raise ValueError("an unreachable leg (target inside the turning circle) has no path")
    arc = None
    if leg.centre is not None and leg.normal is not None:
        arc = {
            "centre": _vec(leg.centre),
            "normal": _vec(leg.normal),
            "angle": float(leg.arc_angle),
            "sense": leg.sense,
            "length": float(leg.arc_length),
        }
    return {
        "start": _vec(leg.start),
        "heading_in": _vec(leg.heading_in),
        "end": _vec(leg.end),
        "radius": float(leg.radius),
        "arc": arc,
        "tangent_point": _vec(leg.tangent_point),
        "heading_out": _vec(leg.heading_out),
        "arc_length": float(leg.arc_length),
        "straight_length": float(leg.straight_length),
        "length": float(leg.length),
    }


def _read_vec(d: dict, key: str) -> np.ndarray:
    try:
        v = np.asarray(d[key], dtype=float)
    except KeyError:
        raise ValueError(f"leg: missing field {key!r}") from None
    except (TypeError, ValueError):
        raise ValueError(f"leg: field {key!r} is not a list of numbers") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"leg: field {key!r} must be three finite numbers")
    return _frozen(v)


def _read_float(d: dict, key: str) -> float:
    try:
        x = float(d[key])
    except KeyError:
        raise ValueError(f"leg: missing field {key!r}") from None
    except (TypeError, ValueError):
        raise ValueError(f"leg: field {key!r} is not a number") from None
    if not math.isfinite(x):
        raise ValueError(f"leg: field {key!r} must be finite")
    return x


def leg_from_dict(d: dict) -> CSLeg:
    """The leg written by ``leg_to_dict``. Raises ``ValueError`` naming a missing or bad field
    (the caller knows the file and turns it into an InputError)."""
    if not isinstance(d, dict):
        raise ValueError("leg: expected an object")
    arc = d.get("arc")
    if arc is not None and not isinstance(arc, dict):
        raise ValueError("leg: field 'arc' must be an object or null")
    return CSLeg(
        start=_read_vec(d, "start"),
        heading_in=_read_vec(d, "heading_in"),
        end=_read_vec(d, "end"),
        radius=_read_float(d, "radius"),
        centre=None if arc is None else _read_vec(arc, "centre"),
        normal=None if arc is None else _read_vec(arc, "normal"),
        arc_angle=0.0 if arc is None else _read_float(arc, "angle"),
        tangent_point=_read_vec(d, "tangent_point"),
        heading_out=_read_vec(d, "heading_out"),
        reachable=True,
    )
