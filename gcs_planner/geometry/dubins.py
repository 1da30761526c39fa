"""3D Dubins "CS" legs: a turn on a circle of radius R, then the straight tangent to the target.

docs/model.md, "Leg geometry". For a leg from Pi (unit heading u) to Pj, with w = Pj - Pi:

    a = w.u,  b = |w - a u| >= 0,  n = (w - a u) / b        (in-plane normal towards j)

In the plane (u, n) the vehicle starts at the origin heading +x and turns towards j on the circle
of radius R centred at (0, R), i.e. C = Pi + R n in 3D. With c = sqrt(a^2 + (b - R)^2):

    t = sqrt(c^2 - R^2)                                      (tangent length)
    phi = ((psi - beta) + pi/2) mod 2 pi,  psi = atan2(b - R, a),  beta = acos(R / c)
    length = R phi + t;  heading at j = cos(phi) u + sin(phi) n

Derivation (checked, and held against a root-finding brute force in the tests): the point of the
arc after turning phi is (R sin phi, R - R cos phi), i.e. at angle theta = phi - pi/2 about C.
The line leaving it along the heading reaches j when (j - C).r = R^2 (tangency) and j lies ahead
of it, which is cos(psi - theta) = R/c with sin(psi - theta) > 0, so theta = psi - beta. The
code evaluates the same angle as one atan2 of the rotated vector (R - b + i a)(R - i t), whose
modulus is c^2, and computes t^2 = a^2 + b^2 - 2 b R, which loses less than c^2 - R^2 does.

The "mod 2 pi" puts the angle in [0, 2 pi]; the only delicate place is phi near 0 = 2 pi,
where a rounding of sin(phi) across zero would turn "no turn" into "a full circle". A target
ahead (a > 0) can only need phi in [0, 3 pi/2] and one behind (a < 0) only phi in [pi/2, 2 pi)
(for phi < pi/2 the tangent point and direction both lead forward, for phi > 3 pi/2 both lead
back). Behind, and with b < R, sin(phi) is a difference of a negative and a positive term and
its sign cannot round wrong; ahead, a - t is rewritten without cancellation (see the code), so
sin(phi) >= 0 whenever b <= 2R and the angle never wraps to 2 pi by accident.

Special cases:

* Straight ahead (b <= 1e-10 |w| and a >= 0): no arc, length |w|, heading unchanged. Points
  closer than 1e-9 m are coincident: a straight leg of length |w| (~0), heading unchanged.
* Straight behind (b <= 1e-10 |w| and a < 0): the plane (u, w) is undefined and the length does
  not depend on it (it is R (2 pi - 2 atan(|a|/R)) + |a|). The normal is then chosen
  deterministically as the horizontal unit vector orthogonal to u on its left, n = z x u / |z x u|
  (a counter-clockwise turn seen from above); for a vertical u, n = y x u.
* R = 0: every leg is the straight chord; the heading at j is the chord direction (unchanged
  for coincident points).
* Target inside the turning circle (c < R, i.e. t^2 < 0): no CS leg reaches it. Policy of this
  project: such a leg is NOT ALLOWED. It is reported with ``reachable=False`` and length
  ``math.inf`` (``cs_lengths`` gives inf and a NaN heading), and the planner never uses it; it
  has no flight path (``point_at``/``sample`` raise ``ValueError``). On the circle itself (c = R)
  the leg is reachable with t = 0, and the length is continuous as c -> R from above.

Everything here is pure numpy, without I/O. ``cs_lengths`` is the vectorised form the planner
calls in its loops; ``cs_leg`` runs the same core on one target, so the two agree to rounding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

TWO_PI = 2.0 * math.pi
# Relative off-axis distance under which a target counts as on the line of the heading. Well above
# the rounding of |u x w| (a few ulp of |w|), well below any distance a route cares about.
STRAIGHT_TOL = 1e-10
# Points closer than this (metres) are one point: a straight leg of that length, heading unchanged.
# Without it, targets a few ulp away would ask for full circles or underflow t^2 to nonsense.
COINCIDENT_M = 1e-9


def _unit(v: np.ndarray, what: str) -> np.ndarray:
    v = np.asarray(v, dtype=float).reshape(3)
    norm = math.sqrt(float(v @ v))
    if not math.isfinite(norm) or norm == 0.0:
        raise ValueError(f"{what} must be a finite non-zero 3-vector, got {v.tolist()}")
    return v / norm


def _point(v: np.ndarray, what: str) -> np.ndarray:
    p = np.asarray(v, dtype=float).reshape(3)
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{what} must be a finite 3-vector, got {p.tolist()}")
    return p


def _check_radius(radius: float) -> float:
    r = float(radius)
    if not math.isfinite(r) or r < 0.0:
        raise ValueError(f"turning radius must be finite and >= 0, got {radius!r}")
    return r


def behind_normal(u: np.ndarray) -> np.ndarray:
    """The normal used when the target is straight behind: horizontal, on the left of u."""
    n = np.array([-u[1], u[0], 0.0])  # z x u
    norm = math.hypot(n[0], n[1])
    if norm < 1e-12:  # u vertical: every horizontal vector qualifies; take y x u
        n = np.array([u[2], 0.0, -u[0]])
        norm = math.sqrt(float(n @ n))
    return n / norm


@dataclass(frozen=True, eq=False)
class _Core:
    """The closed-form solution for m targets from one start and heading (arrays of length m)."""

    length: np.ndarray
    phi: np.ndarray
    normal: np.ndarray  # (m, 3); meaningless where straight
    heading_out: np.ndarray  # (m, 3); NaN where unreachable
    reachable: np.ndarray
    straight: np.ndarray


def _core(start: np.ndarray, u: np.ndarray, ends: np.ndarray, radius: float | np.ndarray) -> _Core:
    """The CS paths of radius ``radius`` (one for all targets, or one > 0 per target)."""
    w = ends - start
    wx, wy, wz = w[:, 0], w[:, 1], w[:, 2]
    ux, uy, uz = float(u[0]), float(u[1]), float(u[2])
    chord = np.sqrt(wx * wx + wy * wy + wz * wz)
    m = w.shape[0]

    if np.ndim(radius) == 0 and radius == 0.0:
        apart = chord > COINCIDENT_M
        heading = np.where(apart[:, None], w / np.where(apart, chord, 1.0)[:, None], u[None, :])
        zeros = np.zeros(m)
        return _Core(
            length=chord,
            phi=zeros,
            normal=np.zeros((m, 3)),
            heading_out=heading,
            reachable=np.ones(m, dtype=bool),
            straight=np.ones(m, dtype=bool),
        )

    a = wx * ux + wy * uy + wz * uz
    # |u x w| keeps its relative accuracy as b -> 0, where |w - a u| would cancel.
    cx = uy * wz - uz * wy
    cy = uz * wx - ux * wz
    cz = ux * wy - uy * wx
    b = np.sqrt(cx * cx + cy * cy + cz * cz)

    coincident = chord <= COINCIDENT_M
    on_axis = (b <= STRAIGHT_TOL * chord) & ~coincident
    behind = on_axis & (a < 0.0)
    b = np.where(behind, 0.0, b)

    perp = w - a[:, None] * u[None, :]
    perp -= (perp @ u)[:, None] * u[None, :]  # second Gram-Schmidt pass: n exactly orthogonal to u
    pn = np.sqrt(np.einsum("ij,ij->i", perp, perp))
    normal = perp / np.where(pn > 0.0, pn, 1.0)[:, None]
    if np.any(behind):
        normal[behind] = behind_normal(u)

    R = radius
    t2 = a * a + b * (b - 2.0 * R)
    reachable = (t2 >= 0.0) | coincident
    # straight ahead only when reachable: a few nanometres ahead and off the axis by more than
    # a^2 / 2R is still inside the circle
    straight = (on_axis & (a >= 0.0) & reachable) | coincident
    t = np.sqrt(np.maximum(t2, 0.0))

    # sin(phi) ~ a R - (R - b) t. Ahead (a > 0) the two terms nearly cancel; a - t is written
    # b (2R - b) / (a + t) there, so that the sign of sin(phi) near phi = 0 is exact.
    # (Only where reachable: inside the circle a + t can be subnormal and the quotient overflow.)
    ahead = (a > 0.0) & (t2 >= 0.0)
    a_minus_t = np.where(ahead, b * (2.0 * R - b) / np.where(ahead, a + t, 1.0), a - t)
    phi = np.arctan2(R * a_minus_t + b * t, (R - b) * R + a * t)
    phi = np.where(phi < 0.0, phi + TWO_PI, phi) + 0.0  # + 0.0: no -0.0 angles
    phi = np.where(straight, 0.0, phi)
    t = np.where(straight, chord, t)

    cos_p = np.cos(phi)[:, None]
    sin_p = np.sin(phi)[:, None]
    heading = cos_p * u[None, :] + sin_p * normal
    heading /= np.sqrt(np.einsum("ij,ij->i", heading, heading))[:, None]
    heading[straight] = u
    heading[~reachable] = np.nan

    length = np.where(straight, chord, R * phi + t)
    length = np.where(reachable, length, math.inf)
    return _Core(
        length=length,
        phi=np.where(reachable, phi, 0.0),
        normal=normal,
        heading_out=heading,
        reachable=reachable,
        straight=straight,
    )


def _frozen(v: np.ndarray) -> np.ndarray:
    v = np.array(v, dtype=float)
    v.setflags(write=False)
    return v


@dataclass(frozen=True, eq=False)
class CSLeg:
    """One leg: the arc from ``start`` (heading ``heading_in``) then the tangent to ``end``.

    Arrays are read-only copies. Equality is identity (numpy arrays have no truth value); compare
    fields when needed.
    """

    start: np.ndarray
    heading_in: np.ndarray
    end: np.ndarray
    radius: float
    centre: np.ndarray | None
    normal: np.ndarray | None
    arc_angle: float
    tangent_point: np.ndarray
    heading_out: np.ndarray
    reachable: bool

    @property
    def arc_length(self) -> float:
        return self.radius * self.arc_angle if self.centre is not None else 0.0

    @property
    def straight_length(self) -> float:
        if not self.reachable:
            return math.inf
        return float(np.linalg.norm(self.end - self.tangent_point))

    @property
    def length(self) -> float:
        if not self.reachable:
            return math.inf
        return self.arc_length + self.straight_length

    @property
    def sense(self) -> int:
        """+1 counter-clockwise seen from above, -1 clockwise, 0 straight or a turn in a vertical
        plane (which has no direction seen from above)."""
        if self.normal is None or self.arc_angle == 0.0:
            return 0
        u, n = self.heading_in, self.normal
        z = u[0] * n[1] - u[1] * n[0]
        if z > 1e-12:
            return 1
        if z < -1e-12:
            return -1
        return 0

    def _need_path(self) -> None:
        if not self.reachable:
            raise ValueError("the target lies inside the turning circle: this leg is not flown")

    def _on_arc(self, angle: float) -> np.ndarray:
        assert self.normal is not None
        r = self.radius
        return (
            self.start
            + r * math.sin(angle) * self.heading_in
            + r * (1.0 - math.cos(angle)) * self.normal
        )

    def _clip(self, s: float) -> float:
        self._need_path()
        total = self.length
        slack = 1e-9 * max(1.0, total)
        if not (-slack <= s <= total + slack):
            raise ValueError(f"distance {s} is outside the leg [0, {total}]")
        return min(max(s, 0.0), total)

    def point_at(self, s: float) -> np.ndarray:
        """Position after flying ``s`` metres along the leg."""
        s = self._clip(float(s))
        arc = self.arc_length
        if s < arc:
            return self._on_arc(s / self.radius)
        return self.tangent_point + (s - arc) * self.heading_out

    def heading_at(self, s: float) -> np.ndarray:
        """Unit heading after flying ``s`` metres along the leg."""
        s = self._clip(float(s))
        arc = self.arc_length
        if s < arc:
            assert self.normal is not None
            angle = s / self.radius
            return math.cos(angle) * self.heading_in + math.sin(angle) * self.normal
        return self.heading_out.copy()

    def sample(self, max_step: float) -> np.ndarray:
        """(k, 3) polyline from start to end: points on the arc (evenly in angle) and on the
        segment, consecutive points at most ``max_step`` apart, the tangent point included."""
        self._need_path()
        if not (max_step > 0.0 and math.isfinite(max_step)):
            raise ValueError(f"max_step must be a positive number, got {max_step!r}")
        parts = [self.start[None, :]]
        arc = self.arc_length
        if arc > 0.0:
            k = max(1, math.ceil(arc / max_step))
            angles = np.linspace(0.0, self.arc_angle, k + 1)[1:]
            assert self.normal is not None
            pts = (
                self.start[None, :]
                + self.radius * np.sin(angles)[:, None] * self.heading_in[None, :]
                + self.radius * (1.0 - np.cos(angles))[:, None] * self.normal[None, :]
            )
            pts[-1] = self.tangent_point
            parts.append(pts)
        seg = self.straight_length
        if seg > 0.0:
            k = max(1, math.ceil(seg / max_step))
            fr = np.linspace(0.0, 1.0, k + 1)[1:, None]
            parts.append(
                self.tangent_point[None, :] + fr * (self.end - self.tangent_point)[None, :]
            )
        out = np.concatenate(parts, axis=0)
        if len(out) == 1:  # zero-length leg: start and end coincide
            out = np.concatenate([out, self.end[None, :]], axis=0)
        out[-1] = self.end
        return out


def straight_leg(
    start: np.ndarray, end: np.ndarray, heading: np.ndarray | None = None, radius: float = 0.0
) -> CSLeg:
    """The chord from ``start`` to ``end``, flown with the chord's own heading (``heading`` is
    used only when the two points coincide). ``radius`` is only recorded: the leg has no arc."""
    R = _check_radius(radius)
    p = _point(start, "start")
    q = _point(end, "end")
    w = q - p
    chord = math.sqrt(float(w @ w))
    if chord > COINCIDENT_M:
        u = w / chord
    elif heading is not None:
        u = _unit(heading, "heading")
    else:
        u = np.array([1.0, 0.0, 0.0])
    return CSLeg(
        start=_frozen(p),
        heading_in=_frozen(u),
        end=_frozen(q),
        radius=R,
        centre=None,
        normal=None,
        arc_angle=0.0,
        tangent_point=_frozen(p),
        heading_out=_frozen(u),
        reachable=True,
    )


def cs_leg(start: np.ndarray, heading: np.ndarray, end: np.ndarray, radius: float) -> CSLeg:
    """The CS leg from ``start`` with unit ``heading`` to ``end`` for turning radius ``radius``.

    ``heading`` need not be normalised. A target inside the turning circle gives a leg with
    ``reachable=False`` and infinite length (see the module docstring).
    """
    p = _point(start, "start")
    q = _point(end, "end")
    u = _unit(heading, "heading")
    R = _check_radius(radius)
    if R == 0.0:
        # No turn to fly: the heading jumps to the chord's at the start (heading_in stays u).
        chord = straight_leg(p, q, u)
        return CSLeg(
            start=chord.start,
            heading_in=_frozen(u),
            end=chord.end,
            radius=0.0,
            centre=None,
            normal=None,
            arc_angle=0.0,
            tangent_point=chord.start,
            heading_out=chord.heading_out,
            reachable=True,
        )
    core = _core(p, u, q[None, :], R)
    reachable = bool(core.reachable[0])
    if bool(core.straight[0]):
        return CSLeg(
            start=_frozen(p),
            heading_in=_frozen(u),
            end=_frozen(q),
            radius=R,
            centre=None,
            normal=None,
            arc_angle=0.0,
            tangent_point=_frozen(p),
            heading_out=_frozen(u),
            reachable=True,
        )
    n = core.normal[0]
    phi = float(core.phi[0])
    if reachable:
        tangent = p + R * math.sin(phi) * u + R * (1.0 - math.cos(phi)) * n
    else:
        tangent = p
    return CSLeg(
        start=_frozen(p),
        heading_in=_frozen(u),
        end=_frozen(q),
        radius=R,
        centre=_frozen(p + R * n),
        normal=_frozen(n),
        arc_angle=phi,
        tangent_point=_frozen(tangent),
        heading_out=_frozen(core.heading_out[0]),
        reachable=reachable,
    )


def cs_lengths(
    start: np.ndarray, heading: np.ndarray, ends: np.ndarray, radius: float
) -> tuple[np.ndarray, np.ndarray]:
    """Flown lengths (m,) and headings at the targets (m, 3) of the CS legs from one start and
    heading to each row of ``ends`` (m, 3). Unreachable targets get inf and a NaN heading."""
    p = _point(start, "start")
    u = _unit(heading, "heading")
    R = _check_radius(radius)
    q = np.asarray(ends, dtype=float)
    if q.ndim != 2 or q.shape[1] != 3:
        raise ValueError(f"ends must have shape (m, 3), got {q.shape}")
    core = _core(p, u, q, R)
    return core.length, core.heading_out
