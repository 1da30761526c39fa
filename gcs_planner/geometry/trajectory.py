"""The flown path of a whole route: one CS leg per hop, each starting with the heading the previous
one ended with (docs/model.md, "Leg geometry"), and its JSON-ready form for the exporters.

Pure numpy, no I/O. A route whose Dubins form has a target inside a turning circle still gives a
``Trajectory`` (its length is inf and ``reachable`` is False) so that the caller can say which leg
fails; it has no polyline.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gcs_planner.geometry.airplane import AirplaneLeg
from gcs_planner.geometry.dubins import COINCIDENT_M, CSLeg, straight_leg
from gcs_planner.geometry.legs import (
    AirplaneLegs,
    CS3DLegs,
    FlownLeg,
    LegModel,
    StraightLegs,
    path_angle_deg,
    scenario_leg_model,
)


@dataclass(frozen=True, eq=False)
class Trajectory:
    """The legs of a route, A first."""

    legs: tuple[FlownLeg, ...]

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
    xyz: np.ndarray,
    radius: float,
    heading_at_a: np.ndarray | None = None,
    model: LegModel | None = None,
) -> Trajectory:
    """The trajectory through the points ``xyz`` (m, 3), A..B, with turning radius ``radius``
    flown as ``model``'s legs (default: the cs3d leg of earlier releases, straight for R = 0).

    With ``heading_at_a`` None the heading at A is free and the first leg is straight (heading at
    A = direction to the first target). Otherwise the first leg turns from it.
    """
    pts = np.asarray(xyz, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2:
        raise ValueError(f"a route needs at least two 3D points (m, 3), got shape {pts.shape}")
    if model is None:
        model = CS3DLegs(radius) if radius > 0 else StraightLegs()
    if heading_at_a is None and not isinstance(model, AirplaneLegs):
        first = straight_leg(pts[0], pts[1], _first_direction(pts), radius)
    else:
        first = model.leg(pts[0], heading_at_a, pts[1])
    legs = [first]
    for k in range(1, pts.shape[0] - 1):
        prev = legs[-1]
        if not prev.reachable:  # no heading to carry on with; the rest cannot be flown either
            heading = prev.heading_in
        else:
            heading = prev.heading_out
        legs.append(model.leg(pts[k], heading, pts[k + 1]))
    return Trajectory(legs=tuple(legs))


def scenario_trajectory(scenario, points: Sequence[int]) -> Trajectory:  # noqa: ANN001
    """The flown trajectory of a route of ``scenario`` under its own leg model."""
    heading = None if scenario.heading_at_a is None else np.asarray(scenario.heading_at_a, float)
    model = scenario_leg_model(scenario)
    return route_trajectory(scenario.xyz[list(points)], scenario.params.turn_radius, heading, model)


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
        "path_angle_deg": path_angle_deg(leg),
        **_airplane_fields(leg),
    }


def _airplane_fields(leg: FlownLeg) -> dict:
    if not isinstance(leg, AirplaneLeg):
        return {"model": "cs3d" if leg.radius > 0 else "straight", "helix_turns": 0}
    return {
        "model": "airplane",
        "helix_turns": int(leg.helix_turns),
        "helix_length": float(leg.helix_length),
        # horizontal normal towards the turn: the side of the helix even on a straight leg
        "turn_normal": None if leg.normal is None else _vec(leg.normal),
        "climb_limit_deg": float(leg.climb_limit_deg),
        "descent_limit_deg": float(leg.descent_limit_deg),
        # metres straight on before the turn (departure waypoint); absent in older plans: 0
        "run_out": float(leg.run_out),
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


def leg_from_dict(d: dict) -> FlownLeg:
    """The leg written by ``leg_to_dict``. Raises ``ValueError`` naming a missing or bad field
    (the caller knows the file and turns it into an InputError)."""
    if not isinstance(d, dict):
        raise ValueError("leg: expected an object")
    if d.get("model") == "airplane":
        return _airplane_from_dict(d)
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


def _airplane_from_dict(d: dict) -> AirplaneLeg:
    turns = d.get("helix_turns", 0)
    if isinstance(turns, bool) or not isinstance(turns, int) or not 0 <= turns <= 10_000:
        raise ValueError("leg: field 'helix_turns' must be a whole number in 0..10000")
    arc = d.get("arc")
    if arc is not None and not isinstance(arc, dict):
        raise ValueError("leg: field 'arc' must be an object or null")
    normal = d.get("turn_normal")
    leg = AirplaneLeg(
        start=_read_vec(d, "start"),
        heading_in=_read_vec(d, "heading_in"),
        end=_read_vec(d, "end"),
        radius=_read_float(d, "radius"),
        normal=None if normal is None else _read_vec(d, "turn_normal"),
        arc_angle=0.0 if arc is None else _read_float(arc, "angle"),
        helix_turns=turns,
        heading_out=_read_vec(d, "heading_out"),
        reachable=True,
        climb_limit_deg=_read_float(d, "climb_limit_deg"),
        descent_limit_deg=_read_float(d, "descent_limit_deg"),
        run_out=_read_float(d, "run_out") if "run_out" in d else 0.0,
    )
    if leg.run_out < 0:
        raise ValueError("leg: field 'run_out' must be >= 0 metres")
    if (turns > 0 or leg.arc_angle > 0) and leg.normal is None:
        raise ValueError("leg: a leg that turns needs its 'turn_normal'")
    if leg.radius < 0 or (turns > 0 and leg.radius == 0):
        raise ValueError("leg: field 'radius' must be > 0 for a leg with a helix")
    return leg
