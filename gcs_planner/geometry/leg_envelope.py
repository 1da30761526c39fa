"""The envelope a leg is flown within from the altitude of its highest point, and the wind
(docs/model.md, "Flight in the real world"): true airspeed by ISA, the radius and the climb and
descent limits it gives, and how much steeper a leg may climb along its own track in a wind of
a stated direction (``track_factor``)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs_planner.aircraft.atmosphere import density_ratios
from gcs_planner.aircraft.profile import G as G_MSS
from gcs_planner.geometry.climb_limits import needed_horizontal_tan, slope_tan
from gcs_planner.geometry.dubins import COINCIDENT_M, TWO_PI


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
