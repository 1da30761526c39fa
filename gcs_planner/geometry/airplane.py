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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs_planner.aircraft.atmosphere import density_ratios
from gcs_planner.aircraft.profile import G as G_MSS
from gcs_planner.geometry.dubins import COINCIDENT_M, TWO_PI, _core

# Rounding slack on "steep enough for a helix": a leg needing 1e-9 m more horizontal path than it
# has is flown without one (the difference is far below anything an aircraft can fly).
STEEP_SLACK_M = 1e-9


@dataclass(frozen=True)
class LegEnvelope:
    """The envelope of each leg from the altitude of its highest point (docs/model.md, "Flight in
    the real world"): the aircraft holds ``eas`` (equivalent airspeed), so its true airspeed and
    with it the ground speed V + W it may turn and climb at grow with altitude (ISA); a leg is
    flown within the limits at its highest point, the most demanding along it (its altitude
    changes monotonically).

    Only for legs that turn (R > 0): straight legs carry no heading, so the search takes them
    from heading-free bounds that must equal them, and those know no altitude.

    ``tan_bank`` 0 keeps ``radius`` for every leg (a radius stated, not derived); a rate of NaN
    keeps the stated angle (``climb_deg``, ``descent_deg``). ``base_altitude`` is the altitude
    (AMSL) of the scenario's z = 0; ``lowest`` its lowest z, where the limits are the most
    permissive, which every heading-free lower bound uses (``bound_*``) so that the bounds stay
    lower bounds whatever the altitudes of the legs they stand for."""

    eas: float
    wind: float
    base_altitude: float
    lowest: float
    radius: float  # the stated radius, or the one at the highest point (displays, B's loiter)
    climb_deg: float
    descent_deg: float
    tan_bank: float = 0.0
    climb_rate: float = math.nan
    sink_rate: float = math.nan
    # The altitude (scenario metres) whose TAS the rates' angles are taken at for every leg
    # (the scenario's highest point: angles not per leg); None: each leg's own.
    angles_at: float | None = None
    # The design wind's direction (degrees it blows from, clockwise from north); None: from
    # any direction. With it, and both angles from rates, each leg climbs within the limit of
    # the fastest ground speed along its own track (``track_factor``).
    wind_from: float | None = None

    @property
    def directional(self) -> bool:
        """Whether the legs' angles follow their tracks in a wind of a stated direction."""
        return (
            self.wind_from is not None and self.wind > 0
            and not math.isnan(self.climb_rate) and not math.isnan(self.sink_rate)
        )  # fmt: skip

    @property
    def wind_vector(self) -> np.ndarray:
        """(east, north) m/s the design wind blows towards; zeros when the angles do not
        follow the tracks (``directional``)."""
        if not self.directional:
            return np.zeros(2)
        return wind_towards(self.wind, float(self.wind_from))  # type: ignore[arg-type]

    def tas(self, z: np.ndarray) -> np.ndarray:
        """True airspeed at each altitude ``z`` (scenario metres; ISA)."""
        sigma = density_ratios(np.asarray(z, dtype=float) + self.base_altitude)
        return self.eas / np.sqrt(sigma)

    def airspeed_at(self, z: np.ndarray) -> np.ndarray:
        """The TAS the climb and descent limits at each altitude ``z`` are taken at."""
        z = np.asarray(z, dtype=float)
        if self.angles_at is not None:
            return np.full(z.shape, float(self.tas(np.array([self.angles_at]))[0]))
        return self.tas(z)

    def at(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(radius, tan climb limit, tan descent limit) at each altitude ``z`` (scenario
        metres), from any direction: non-decreasing radius and non-increasing tangents as z
        grows."""
        z = np.asarray(z, dtype=float)
        v = self.tas(z) + self.wind
        if self.tan_bank > 0:
            radius = v * v / (G_MSS * self.tan_bank)
        else:
            radius = np.full(z.shape, float(self.radius))
        va = self.airspeed_at(z) + self.wind
        return (
            radius,
            self._tan(self.climb_rate, self.climb_deg, va),
            self._tan(self.sink_rate, self.descent_deg, va),
        )

    def airspeeds(self, z_start: float, z_ends: np.ndarray) -> np.ndarray:
        """The TAS each leg's limits are taken at (``of_legs``: the higher end's)."""
        return np.maximum(self.airspeed_at(np.asarray(z_ends, dtype=float)),
                          float(self.airspeed_at(np.array([z_start]))[0]))  # fmt: skip

    def bound_factor(
        self,
        w: np.ndarray,
        airspeed: np.ndarray,
        tan_climb: np.ndarray | float,
        tan_descent: np.ndarray | float,
    ) -> np.ndarray:
        """How much steeper than from any direction (tangents ``tan_climb``, ``tan_descent``)
        a lower bound of any leg over the offsets ``w`` ((m, 3)) may take it, whatever its
        track (docs/model.md, "Flight in the real world"): need / the least horizontal path
        ``least_horizontal`` allows, need = |dz| / tan; 1 where the wind has no direction."""
        if not self.directional:
            return np.ones(len(w))
        w = np.asarray(w, dtype=float)
        need = needed_horizontal_tan(w[:, 2], tan_climb, tan_descent)
        least = self.least_horizontal(w, airspeed, need)
        return np.where(need > 0.0, need / np.where(least > 0.0, least, 1.0), 1.0)

    def least_horizontal(self, w: np.ndarray, airspeed: np.ndarray, need: np.ndarray) -> np.ndarray:
        """A lower bound of the horizontal path of any leg over the offsets ``w`` ((m, 2+),
        chord length h at angle a off downwind) that needs ``need`` metres from any direction,
        flown at the TAS ``airspeed``. Let b be the angle off downwind of the leg's heading
        nearest to it: the leg may be steeper by f(b) = (V + W) / Vg(b) (``track_factor``), so
        its path L >= need / f(b); every heading t has t.downwind <= cos b and the headings
        sum to the chord, so L cos b >= h cos a. Where a >= 90 deg no track has b > a (its
        headings, all within 180 - b < 90 deg of upwind, cannot sum to the chord), so
        L >= max(h, need / f(a)); downwind, L >= min over b in [a, 90 deg) of
        max(h cos a / cos b, need / f(b)), the first rising and the second falling in b: found
        by bisection and taken at the bracket's safe ends. Where the points coincide, V - W."""
        w = np.asarray(w, dtype=float)
        need = np.asarray(need, dtype=float)
        v = np.asarray(airspeed, dtype=float) * np.ones(len(w))
        wind = self.wind
        h = np.hypot(w[:, 0], w[:, 1])
        apart = h > COINCIDENT_M
        downwind = self.wind_vector / wind
        cos_a = np.where(apart, (w[:, 0] * downwind[0] + w[:, 1] * downwind[1])
                         / np.where(apart, h, 1.0), 1.0)  # fmt: skip
        cos_a = np.clip(cos_a, -1.0, 1.0)
        scale = need / (v + wind)  # need / f(b) = scale * Vg(b)
        steep = scale * _ground_speed_off_downwind(cos_a, v, wind)
        least = np.maximum(h, steep)
        # Only downwind chords whose own angle leaves the bound above h gain from a search
        # of b (most pairs do not: the bisection runs on those alone).
        i = np.flatnonzero(apart & (cos_a > 0.0) & (steep > h))
        if len(i):
            hi_, ca, vi, si = h[i], cos_a[i], v[i], scale[i]
            lo = np.arccos(ca)
            hi = np.full(len(i), math.pi / 2)
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                up = hi_ * ca / np.cos(mid) < si * _ground_speed_off_downwind(np.cos(mid), vi, wind)
                lo = np.where(up, mid, lo)
                hi = np.where(up, hi, mid)
            rising = hi_ * ca / np.cos(lo)
            best = np.maximum(rising, si * _ground_speed_off_downwind(np.cos(hi), vi, wind))
            least[i] = np.minimum(best, least[i])
        least = np.where(apart, least, scale * (v - wind))
        return least * (1.0 - 1e-9)

    @staticmethod
    def _tan(rate: float, angle_deg: float, v: np.ndarray) -> np.ndarray:
        if math.isnan(rate):
            return np.full(v.shape, slope_tan(angle_deg))
        if math.isinf(rate):
            return np.full(v.shape, math.inf)
        return rate / v

    def of_legs(
        self, z_start: float, z_ends: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(radius, tan climb, tan descent) of the legs from altitude ``z_start`` to each of
        ``z_ends``: the limits at the higher end of each (the largest radius, the smallest
        tangents; taken as the extreme of both ends so that the compiled search, which has them
        per point, gets the same numbers)."""
        r0, c0, d0 = self.at(np.array([z_start]))
        r, c, d = self.at(z_ends)
        return np.maximum(r, r0[0]), np.minimum(c, c0[0]), np.minimum(d, d0[0])

    def bounds(self) -> tuple[float, float, float]:
        """(radius, tan climb, tan descent) at the lowest altitude, loosened by a part in 1e9
        against rounding: at least as permissive as any leg's. In a wind of a stated direction
        the angles are those of flying straight into it (V - W: the slowest ground speed any
        track has), so that they hold whatever the legs' tracks."""
        r, c, d = (float(x[0]) for x in self.at(np.array([self.lowest])))
        if self.directional:
            v = float(self.airspeed_at(np.array([self.lowest]))[0])
            c, d = (x * (v + self.wind) / (v - self.wind) for x in (c, d))
        return r * (1.0 - 1e-9), c * (1.0 + 1e-9), d * (1.0 + 1e-9)


def wind_towards(speed: float, from_deg: float) -> np.ndarray:
    """(east, north) m/s of a wind of ``speed`` blowing from ``from_deg`` (clockwise from
    north, as a wind is reported): the vector it blows towards."""
    a = math.radians(from_deg)
    return np.array([-speed * math.sin(a), -speed * math.cos(a)])


def slope_limit(climb_deg: float, descent_deg: float, dz: np.ndarray | float) -> np.ndarray:
    """tan(gamma) for each dz (climb limit for dz > 0, descent for dz < 0); inf for 90 deg."""
    dz = np.asarray(dz, dtype=float)
    return np.where(dz > 0, slope_tan(climb_deg), slope_tan(descent_deg))


def slope_tan(angle_deg: float) -> float:
    """tan of a climb or descent limit in degrees; inf for 90 (no limit)."""
    return math.inf if angle_deg >= 90.0 else math.tan(math.radians(angle_deg))


def needed_horizontal(dz: np.ndarray, climb_deg: float, descent_deg: float) -> np.ndarray:
    """The least horizontal path (m) on which the aircraft can change altitude by ``dz``."""
    dz = np.asarray(dz, dtype=float)
    g = slope_limit(climb_deg, descent_deg, dz)
    return np.where(np.isinf(g), 0.0, np.abs(dz) / np.where(np.isinf(g), 1.0, g))


def helix_turns(
    horizontal: np.ndarray,
    need: np.ndarray,
    radius: float | np.ndarray,
    steeper: np.ndarray | float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """(k, feasible): whole helix turns so that horizontal + 2 pi R k >= need; with R = 0 a leg
    that needs more horizontal path than it has is infeasible. ``radius`` one for all legs or
    one per leg (a per-leg envelope; all > 0 then). A leg with no helix may be ``steeper``
    times as steep as ``need`` says (its own track in a wind of a stated direction,
    ``track_factor``); a helix flies every heading, so its turns are counted from ``need``."""
    horizontal = np.asarray(horizontal, dtype=float)
    short = need / steeper - horizontal > STEEP_SLACK_M
    if np.ndim(radius) == 0 and radius <= 0.0:
        return np.zeros(horizontal.shape, dtype=np.int64), ~short
    k = np.where(short, np.ceil((need - horizontal - STEEP_SLACK_M) / (TWO_PI * radius)), 0.0)
    return np.maximum(k, 0).astype(np.int64), np.ones(horizontal.shape, dtype=bool)


def track_factor(
    u: np.ndarray, normal: np.ndarray, phi: np.ndarray, airspeed: np.ndarray, wind: np.ndarray
) -> np.ndarray:
    """(V + W) / the fastest ground speed of each leg over its track's headings, from ``u``
    turning towards ``normal`` through ``phi`` ((m, 2+) unit vectors, (m,) angles): how much
    steeper than from any direction the leg may climb at the rates (docs/model.md, "Flight in
    the real world"); 1 with no wind. ``wind`` is (east, north) m/s, where it blows towards.
    A run-out flies u and the tangent the arc's last heading, so the arc's headings are all
    the leg's; downwind within them gives V + W, else the faster of the two ends (the ground
    speed falls with the angle off downwind). ``airplane_kernel.track_factor`` does the same
    operations."""
    m = len(phi)
    w = math.hypot(float(wind[0]), float(wind[1]))
    if w == 0.0:
        return np.ones(m)
    wx, wy = float(wind[0]), float(wind[1])
    u = np.asarray(u, dtype=float)
    n = np.asarray(normal, dtype=float)
    phi = np.asarray(phi, dtype=float)
    v = np.asarray(airspeed, dtype=float)
    ux, uy, nx, ny = u[:, 0], u[:, 1], n[:, 0], n[:, 1]
    fastest = _ground_speed(ux, uy, v, wx, wy)
    c, s = np.cos(phi), np.sin(phi)
    fastest = np.maximum(fastest, _ground_speed(c * ux + s * nx, c * uy + s * ny, v, wx, wy))
    turned = np.arctan2((wx * nx + wy * ny) / w, (wx * ux + wy * uy) / w)
    turned = np.where(turned < 0.0, turned + TWO_PI, turned)
    fastest = np.where((phi > 0.0) & (turned <= phi), v + w, fastest)
    return np.maximum((v + w) / fastest, 1.0)


def _ground_speed_off_downwind(cos_b: np.ndarray, airspeed: np.ndarray, wind: float) -> np.ndarray:
    """The ground speed along a track at angle b off downwind (from its cosine), TAS
    ``airspeed`` in a wind of ``wind`` m/s: W cos b + sqrt(V^2 - W^2 sin^2 b)."""
    return wind * cos_b + np.sqrt(np.maximum(airspeed**2 - wind * wind * (1.0 - cos_b**2), 0.0))


def _ground_speed(tx, ty, airspeed, wx: float, wy: float):  # noqa: ANN001, ANN202 - arrays
    along = wx * tx + wy * ty
    cross = wx * ty - wy * tx
    return along + np.sqrt(np.maximum(airspeed * airspeed - cross * cross, 0.0))


def needed_horizontal_tan(
    dz: np.ndarray, tan_climb: float | np.ndarray, tan_descent: float | np.ndarray
) -> np.ndarray:
    """``needed_horizontal`` from the tangents of the limits (inf: no limit), one for all legs
    or one per leg: |dz| / tan(gamma), 0 where unlimited."""
    dz = np.asarray(dz, dtype=float)
    g = np.where(dz > 0, tan_climb, tan_descent)
    return np.where(np.isinf(g), 0.0, np.abs(dz) / np.where(np.isinf(g), 1.0, g))


def lower_bounds(
    start: np.ndarray, ends: np.ndarray, climb_deg: float, descent_deg: float, radius: float
) -> np.ndarray:
    """Heading-free lower bounds of the airplane legs from ``start`` to each row of ``ends``:
    max(chord, |dz| / sin gamma), or inf where R = 0 and the straight leg is too steep."""
    return lower_bounds_tan(start, ends, slope_tan(climb_deg), slope_tan(descent_deg), radius)


def lower_bounds_tan(
    start: np.ndarray, ends: np.ndarray, tan_climb: float, tan_descent: float, radius: float
) -> np.ndarray:
    """``lower_bounds`` from the tangents of the limits (inf: no limit)."""
    w = np.asarray(ends, dtype=float) - np.asarray(start, dtype=float)
    h = np.hypot(w[:, 0], w[:, 1])
    dz = w[:, 2]
    need = needed_horizontal_tan(dz, tan_climb, tan_descent)
    out = np.sqrt(np.maximum(h, need) ** 2 + dz * dz)
    if radius <= 0.0:
        out = np.where(need - h > STEEP_SLACK_M, math.inf, out)
    return out


@dataclass(frozen=True, eq=False)
class _Horizontal:
    length: np.ndarray  # H
    phi: np.ndarray
    normal: np.ndarray  # (m, 3) horizontal unit normals towards the turn (meaningless if straight)
    heading: np.ndarray  # (m, 3) horizontal headings at the targets
    reachable: np.ndarray
    straight: np.ndarray


def _horizontal(
    start: np.ndarray,
    heading: np.ndarray | None,
    ends: np.ndarray,
    radius: float,
    run_in: float = 0.0,
    run_out: float = 0.0,
):
    flat_start = np.array([start[0], start[1], 0.0])
    flat_ends = np.column_stack([ends[:, 0], ends[:, 1], np.zeros(len(ends))])
    if heading is None:
        w = flat_ends - flat_start
        h = np.hypot(w[:, 0], w[:, 1])
        apart = h > COINCIDENT_M
        dirs = np.where(apart[:, None], w / np.where(apart, h, 1.0)[:, None], [1.0, 0.0, 0.0])
        ones = np.ones(len(ends), dtype=bool)
        return _Horizontal(h, np.zeros(len(ends)), _left_of(dirs), dirs, h >= run_in, ones)
    u = np.array([heading[0], heading[1], 0.0])
    u /= math.hypot(u[0], u[1])
    turn_start = flat_start + run_out * u
    core = _core(turn_start, u, flat_ends, radius)
    # A straight-ahead leg holds its helix on the left (either side gives the same length).
    left = _left_of(np.broadcast_to(u, (len(ends), 3)))
    normal = np.where(core.straight[:, None], left, core.normal)
    reachable = core.reachable
    if run_in > 0.0:
        reachable = reachable & (tangent_lengths(turn_start, u, flat_ends, radius) >= run_in)
    return _Horizontal(
        run_out + core.length, core.phi, normal, core.heading_out, reachable, core.straight
    )


def tangent_lengths(
    start: np.ndarray, u: np.ndarray, ends: np.ndarray, radius: float
) -> np.ndarray:
    """Horizontal length of the straight part (the tangent) of the CS paths from ``start`` with
    horizontal unit heading ``u`` to each row of ``ends``: sqrt(a^2 + b (b - 2R)), a and b the
    target's offset along and across u (the chord when the target lies straight ahead, 0 when
    it lies on the start; NaN never: inside the circle gives 0). ``airplane_kernel`` computes it
    with the same operations, so that both agree on which legs have their run-in."""
    wx = ends[:, 0] - start[0]
    wy = ends[:, 1] - start[1]
    a = wx * u[0] + wy * u[1]
    b = np.abs(u[0] * wy - u[1] * wx)
    return np.sqrt(np.maximum(a * a + b * (b - 2.0 * radius), 0.0))


def _left_of(dirs: np.ndarray) -> np.ndarray:
    """Horizontal unit vectors on the left of each horizontal direction (z x d)."""
    return np.column_stack([-dirs[:, 1], dirs[:, 0], np.zeros(len(dirs))])


@dataclass(frozen=True, eq=False)
class AirplaneLegs:
    """The airplane legs from one start and heading to many targets (vectorised)."""

    length: np.ndarray  # inf where not flyable
    heading: np.ndarray  # (m, 3) horizontal heading at each target; NaN where not flyable
    horizontal: np.ndarray  # H + 2 pi R k (H with the run-out)
    helix_turns: np.ndarray  # k
    arc_angle: np.ndarray  # phi
    normal: np.ndarray  # (m, 3) horizontal normal towards the turn (and the helix)
    straight: np.ndarray  # no arc
    # how much steeper than its limits from any direction each leg may climb along its own
    # track (a design wind of a stated direction; 1 without, and not used where a helix flies)
    steeper: np.ndarray | None = None


def airplane_legs(
    start: np.ndarray,
    heading: np.ndarray | None,
    ends: np.ndarray,
    radius: float,
    climb_deg: float,
    descent_deg: float,
    run_in: float = 0.0,
    run_out: float = 0.0,
    envelope: LegEnvelope | None = None,
) -> AirplaneLegs:
    """Airplane legs from ``start`` (horizontal ``heading``, None = free: straight legs) to each
    row of ``ends``, with a run-out of ``run_out`` and a tangent of at least ``run_in`` metres
    (horizontal; both 0 with R = 0: straight legs carry no heading to run out on).

    With an ``envelope`` each leg turns on the radius and climbs within the limits of its own
    highest point (``LegEnvelope.of_legs``; ``radius`` and the angles are then not used)."""
    start = np.asarray(start, dtype=float)
    ends = np.asarray(ends, dtype=float)
    if envelope is not None:
        radius, tan_climb, tan_descent = envelope.of_legs(start[2], ends[:, 2])
    else:
        tan_climb, tan_descent = slope_tan(climb_deg), slope_tan(descent_deg)
    straight = np.ndim(radius) == 0 and radius <= 0
    if straight:
        run_in = run_out = 0.0
    hz = _horizontal(start, None if straight else heading, ends, radius, run_in, run_out)
    dz = ends[:, 2] - start[2]
    need = needed_horizontal_tan(dz, tan_climb, tan_descent)
    steeper = np.ones(len(ends))
    if envelope is not None and envelope.directional and not straight:
        u = hz.heading if heading is None else np.broadcast_to(
            np.asarray(heading, dtype=float)[:2] / math.hypot(heading[0], heading[1]),
            (len(ends), 2),
        )  # fmt: skip
        with np.errstate(invalid="ignore"):
            steeper = track_factor(
                u, hz.normal, np.where(hz.reachable, hz.phi, 0.0),
                envelope.airspeeds(start[2], ends[:, 2]), envelope.wind_vector,
            )  # fmt: skip
    k, ok = helix_turns(hz.length, need, radius, steeper)
    ok &= hz.reachable
    flat = hz.length + TWO_PI * radius * k
    length = np.where(ok, np.sqrt(flat * flat + dz * dz), math.inf)
    head = np.where(ok[:, None], hz.heading, np.nan)
    return AirplaneLegs(length, head, flat, k, hz.phi, hz.normal, hz.straight, steeper)


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
