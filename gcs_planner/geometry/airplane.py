"""Airplane legs (docs/model.md, "Airplane legs"; Owen, Beard & McLain's Dubins airplane).

The aircraft's heading is horizontal. A leg from Pi (horizontal unit heading u) to Pj is:

* the horizontal CS path of ``dubins`` done in the x-y plane: an arc of radius R towards j, then
  the tangent; its horizontal length H = R phi + t;
* altitude dz = zj - zi spread evenly over the leg (one flight-path angle for the whole leg);
* when the leg is too steep for its horizontal length (H < |dz| / tan gamma, gamma the climb
  limit for dz > 0 and the descent limit for dz < 0), first k whole turns on the leg's turning
  circle (a helix, in the sense of the arc), k the least integer with H + 2 pi R k >= |dz| / tan
  gamma. The heading at j does not change with the helix: the turns are whole.

Flown length sqrt((H + 2 pi R k)^2 + dz^2). With R = 0 a too-steep leg cannot be flown (no helix):
its length is inf. A heading-free lower bound of any leg is sqrt(max(h, |dz|/tan gamma)^2 + dz^2)
= max(|w|, |dz| / sin gamma) (h the horizontal distance): the straight leg under the same limits.
It is subadditive (the maximum of a norm and a sublinear function of dz), so sums of it along a
walk bound the straight distance-like cost-to-go from below as the chord did.

The leg is flown in this order: the helix (starting and ending at Pi's horizontal position, with
Pi's heading), then the arc, then the tangent; the altitude changes at the same rate throughout.

Straight at every landmark (docs/model.md, "Straight at every landmark"): with a run-out s_out > 0
the leg first flies s_out metres straight on, along the heading it arrived with at Pi (the
departure waypoint), and its helix and arc start there; with a run-in s_in > 0 its tangent into
Pj must be at least s_in metres long, so that the aircraft is settled on the line before it
overflies the landmark. A leg whose tangent is shorter is not flown (like a target inside the
turning circle). The first leg from a free heading at A is straight: it has no run-out and needs
h >= s_in. Both are horizontal metres, part of H and so of the flown length and the errors.

One leg with its geometry (``AirplaneLeg``, ``airplane_leg``) is here; the rest of the model is
split by purpose, its names still importable from here: the climb and descent limits, helix
turns and heading-free bounds (``climb_limits``), the envelope and the wind (``leg_envelope``),
and the legs to many targets at once (``airplane_fan``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs_planner.geometry.airplane_fan import AirplaneLegs, airplane_legs, tangent_lengths
from gcs_planner.geometry.climb_limits import (
    STEEP_SLACK_M,
    helix_turns,
    lower_bounds,
    lower_bounds_tan,
    needed_horizontal,
    needed_horizontal_tan,
    slope_limit,
    slope_tan,
)
from gcs_planner.geometry.dubins import COINCIDENT_M, TWO_PI
from gcs_planner.geometry.leg_envelope import LegEnvelope, track_factor, wind_towards

__all__ = [
    "STEEP_SLACK_M",
    "AirplaneLeg",
    "AirplaneLegs",
    "LegEnvelope",
    "airplane_leg",
    "airplane_legs",
    "helix_turns",
    "lower_bounds",
    "lower_bounds_tan",
    "needed_horizontal",
    "needed_horizontal_tan",
    "slope_limit",
    "slope_tan",
    "tangent_lengths",
    "track_factor",
    "wind_towards",
]


@dataclass(frozen=True, eq=False)
class AirplaneLeg:
    """One airplane leg with its geometry: helix, arc, tangent, and the altitude along them.

    Positions use the same names as ``dubins.CSLeg`` (start, end, centre, normal, arc_angle,
    tangent_point, heading_in/out), so that exporters and pictures read either; ``centre`` and
    ``tangent_point`` are horizontal positions given at the altitude the aircraft has there.
    """

    start: np.ndarray
    heading_in: np.ndarray
    end: np.ndarray
    radius: float
    normal: np.ndarray | None  # horizontal, towards the turn; None for a straight leg, no helix
    arc_angle: float
    helix_turns: int
    heading_out: np.ndarray
    reachable: bool
    climb_limit_deg: float = 90.0
    descent_limit_deg: float = 90.0
    # Horizontal metres flown straight on along ``heading_in`` before the helix and the arc (the
    # run-out to the departure waypoint; docs/model.md, "Straight at every landmark").
    run_out: float = 0.0

    # -- lengths (horizontal first, then along the climbing path) --

    @property
    def dz(self) -> float:
        return float(self.end[2] - self.start[2])

    @property
    def helix_horizontal(self) -> float:
        return TWO_PI * self.radius * self.helix_turns

    @property
    def arc_horizontal(self) -> float:
        return self.radius * self.arc_angle if self.normal is not None else 0.0

    @property
    def _turn_start_flat(self) -> np.ndarray:
        """Horizontal position where the run-out ends and the helix and the arc start."""
        return self.start[:2] + self.run_out * self.heading_in[:2]

    @property
    def departure_point(self) -> np.ndarray | None:
        """Where the run-out ends (the departure waypoint), at the plan's altitude there; None
        without a run-out."""
        return self.point_at_horizontal(self.run_out) if self.run_out > 0 else None

    @property
    def _tangent_flat(self) -> np.ndarray:
        """Horizontal position where the arc ends."""
        p = self._turn_start_flat
        if self.normal is None or self.arc_angle == 0.0:
            return p.copy()
        u, n, r, a = self.heading_in[:2], self.normal[:2], self.radius, self.arc_angle
        return p + r * math.sin(a) * u + r * (1.0 - math.cos(a)) * n

    @property
    def straight_horizontal(self) -> float:
        return float(np.linalg.norm(self.end[:2] - self._tangent_flat))

    @property
    def horizontal_length(self) -> float:
        return self.run_out + self.helix_horizontal + self.arc_horizontal + self.straight_horizontal

    @property
    def _scale(self) -> float:
        """Flown metres per horizontal metre (1 / cos of the flight-path angle)."""
        h = self.horizontal_length
        return math.hypot(h, self.dz) / h if h > 0 else 1.0

    @property
    def length(self) -> float:
        if not self.reachable:
            return math.inf
        return math.hypot(self.horizontal_length, self.dz)

    @property
    def helix_length(self) -> float:
        return self.helix_horizontal * self._scale

    @property
    def arc_length(self) -> float:
        """The turning part of the leg (helix and arc), flown metres."""
        return (self.helix_horizontal + self.arc_horizontal) * self._scale

    @property
    def straight_length(self) -> float:
        return self.straight_horizontal * self._scale if self.reachable else math.inf

    @property
    def path_angle(self) -> float:
        """Flight-path angle in degrees (positive climbing)."""
        return math.degrees(math.atan2(self.dz, self.horizontal_length))

    @property
    def centre(self) -> np.ndarray | None:
        """Centre of the turning circle (horizontal), at the start's altitude."""
        if self.normal is None:
            return None
        turn_start = np.array([*self._turn_start_flat, self.start[2]])
        return turn_start + self.radius * self.normal

    @property
    def tangent_point(self) -> np.ndarray:
        return self.point_at_horizontal(self.run_out + self.helix_horizontal + self.arc_horizontal)

    @property
    def sense(self) -> int:
        """+1 counter-clockwise seen from above, -1 clockwise, 0 when the leg never turns."""
        if self.normal is None or (self.arc_angle == 0.0 and self.helix_turns == 0):
            return 0
        u, n = self.heading_in, self.normal
        return 1 if u[0] * n[1] - u[1] * n[0] > 0 else -1

    # -- positions --

    def _altitude(self, s_h: float) -> float:
        h = self.horizontal_length
        return float(self.start[2] + (self.dz * s_h / h if h > 0 else self.dz))

    def point_at_horizontal(self, s_h: float) -> np.ndarray:
        """Position after ``s_h`` horizontal metres along the leg."""
        return self.points_at_horizontal(np.array([float(s_h)]))[0]

    def points_at_horizontal(self, s_h: np.ndarray) -> np.ndarray:
        """(m, 3) positions after each of ``s_h`` horizontal metres along the leg."""
        if not self.reachable:
            raise ValueError("the target lies inside the turning circle: this leg is not flown")
        s_h = np.clip(np.asarray(s_h, dtype=float), 0.0, self.horizontal_length)
        h = self.horizontal_length
        z = self.start[2] + (self.dz * s_h / h if h > 0 else np.full(len(s_h), self.dz))
        ro = self.run_out
        turning = ro + self.helix_horizontal + self.arc_horizontal
        xy = np.empty((len(s_h), 2))
        running_out = s_h < ro
        xy[running_out] = self.start[:2] + s_h[running_out, None] * self.heading_in[:2]
        on_circle = (s_h < turning) & ~running_out
        if self.normal is not None and self.radius > 0 and on_circle.any():
            # the angle turned; the helix is whole turns, so the position repeats every 2 pi
            a = (s_h[on_circle] - ro) / self.radius
            u, n, r = self.heading_in[:2], self.normal[:2], self.radius
            xy[on_circle] = (
                self._turn_start_flat
                + r * np.sin(a)[:, None] * u
                + r * (1.0 - np.cos(a))[:, None] * n
            )
        else:
            on_circle[:] = False
        rest = ~on_circle & ~running_out
        if rest.any():
            flat0 = self._tangent_flat
            span = self.end[:2] - flat0
            dist = float(np.linalg.norm(span))
            frac = np.zeros(rest.sum()) if dist == 0 else (s_h[rest] - turning) / dist
            xy[rest] = flat0 + np.clip(frac, 0.0, 1.0)[:, None] * span
        return np.column_stack([xy, z])

    def point_at(self, s: float) -> np.ndarray:
        """Position after flying ``s`` metres along the leg."""
        return self.point_at_horizontal(float(s) / self._scale)

    def heading_at(self, s: float) -> np.ndarray:
        """Horizontal unit heading after flying ``s`` metres."""
        s_h = float(s) / self._scale - self.run_out
        turning = self.helix_horizontal + self.arc_horizontal
        if s_h < 0.0:
            return self.heading_in.copy()
        if s_h < turning and self.normal is not None and self.radius > 0:
            a = s_h / self.radius
            return math.cos(a) * self.heading_in + math.sin(a) * self.normal
        return self.heading_out.copy()

    def sample(self, max_step: float) -> np.ndarray:
        """(k, 3) polyline from start to end, consecutive points at most ``max_step`` apart
        horizontally (and along the path), the helix's end and the tangent point included."""
        if not self.reachable:
            raise ValueError("the target lies inside the turning circle: this leg is not flown")
        if not (max_step > 0.0 and math.isfinite(max_step)):
            raise ValueError(f"max_step must be a positive number, got {max_step!r}")
        marks = [0.0]
        ro = self.run_out
        turning = ro + self.helix_horizontal + self.arc_horizontal
        for lo, hi in ((0.0, ro), (ro, turning), (turning, self.horizontal_length)):
            if hi > lo:
                k = max(1, math.ceil((hi - lo) / max_step))
                marks.extend(np.linspace(lo, hi, k + 1)[1:].tolist())
        if self.helix_horizontal > 0:
            marks.append(ro + self.helix_horizontal)
        marks = sorted(set(marks))
        out = self.points_at_horizontal(np.array(marks))
        if len(out) == 1:
            out = np.concatenate([out, self.end[None, :]], axis=0)
        out[-1] = self.end
        return out


def airplane_leg(
    start: np.ndarray,
    heading: np.ndarray | None,
    end: np.ndarray,
    radius: float,
    climb_deg: float,
    descent_deg: float,
    run_in: float = 0.0,
    run_out: float = 0.0,
    envelope: LegEnvelope | None = None,
) -> AirplaneLeg:
    """The airplane leg from ``start`` (horizontal ``heading``; None = free) to ``end``, with
    its run-out and run-in (``airplane_legs``); with an ``envelope``, on the radius and within
    the limits of its own highest point (which it records)."""
    p = np.asarray(start, dtype=float).reshape(3)
    q = np.asarray(end, dtype=float).reshape(3)
    legs = airplane_legs(
        p, heading, q[None, :], radius, climb_deg, descent_deg, run_in, run_out, envelope
    )
    if envelope is not None:
        r, c, d = (float(x[0]) for x in envelope.of_legs(p[2], q[2:3]))
        if legs.helix_turns[0] == 0 and legs.steeper is not None:
            # its own track's limits (a wind of a stated direction); a helix flies them all
            c, d = c * float(legs.steeper[0]), d * float(legs.steeper[0])
        radius = r
        climb_deg, descent_deg = _degrees(c), _degrees(d)
    runs_out = heading is not None and radius > 0
    reachable = bool(np.isfinite(legs.length[0]))
    if heading is None or radius <= 0:
        w = q[:2] - p[:2]
        h = math.hypot(*w)
        u = np.array([w[0] / h, w[1] / h, 0.0]) if h > COINCIDENT_M else np.array([1.0, 0, 0])
        if heading is not None and h <= COINCIDENT_M:
            u = np.array([heading[0], heading[1], 0.0]) / math.hypot(heading[0], heading[1])
    else:
        u = np.array([heading[0], heading[1], 0.0]) / math.hypot(heading[0], heading[1])
    k = int(legs.helix_turns[0])
    phi = float(legs.arc_angle[0]) if reachable and radius > 0 else 0.0
    turns = k > 0 or phi > 0.0
    normal = legs.normal[0] if turns and radius > 0 else None
    if normal is not None and heading is None:
        normal = np.array([-u[1], u[0], 0.0])  # free heading: a straight leg, helix on the left
    out = legs.heading[0] if reachable else u
    return AirplaneLeg(
        start=_frozen(p),
        heading_in=_frozen(u),
        end=_frozen(q),
        radius=float(radius),
        normal=None if normal is None else _frozen(normal),
        arc_angle=phi,
        helix_turns=k,
        heading_out=_frozen(out),
        reachable=reachable,
        climb_limit_deg=climb_deg,
        descent_limit_deg=descent_deg,
        run_out=float(run_out) if runs_out else 0.0,
    )


def _degrees(tan: float) -> float:
    return 90.0 if math.isinf(tan) else math.degrees(math.atan(tan))


def _frozen(v: np.ndarray) -> np.ndarray:
    v = np.array(v, dtype=float)
    v.setflags(write=False)
    return v
