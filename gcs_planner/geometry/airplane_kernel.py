"""Airplane legs from a heading, compiled (numba): ``airplane.airplane_legs`` for searches that
fly thousands of partial routes (the branch and bound with turns asks it once per label, for a
dozen targets, where numpy's cost per call is most of the time).

The horizontal CS path of ``dubins_kernel.cs_core`` (``dubins._core``'s formulas in the plane) and
``airplane.airplane_legs`` (the helix turns and the flown length); only the sums of three
products may round differently (numpy's matrix product may fuse them), so lengths and headings
agree to a few ulp (tested), not bit for bit.
"""

from __future__ import annotations

import math

import numpy as np

from gcs_planner.geometry.airplane import STEEP_SLACK_M
from gcs_planner.geometry.dubins import COINCIDENT_M, TWO_PI
from gcs_planner.geometry.dubins_kernel import cs_arc
from gcs_planner.runtime.jit import inner, kernel


@kernel
def airplane_lengths(
    start: np.ndarray,
    heading: np.ndarray,
    ends: np.ndarray,
    radius: float,
    tan_climb: float,
    tan_descent: float,
    run_in: float = 0.0,
    run_out: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """(flown lengths, horizontal headings at the targets (m, 3)) of the airplane legs from
    ``start`` with horizontal ``heading`` to each row of ``ends``; inf and NaN where a target
    lies inside the turning circle or its tangent is shorter than ``run_in``; tangents inf for
    limits of 90 degrees. The leg first runs ``run_out`` metres straight on. ``radius`` 0 flies
    the chord whatever the heading, and a leg too steep for it is inf (no helix), as numpy's."""
    m = ends.shape[0]
    r = np.full(m, radius)
    tc = np.full(m, tan_climb)
    td = np.full(m, tan_descent)
    # still air: the legs' angles do not follow their tracks, so their airspeeds are not read
    no_wind = np.zeros(2)
    airspeed = np.zeros(m)
    if radius <= 0.0:
        return free_airplane_lengths(start, ends, r, tc, td, 0.0, airspeed, no_wind)
    return airplane_lengths_each(
        start, heading, ends, r, tc, td, run_in, run_out, airspeed, no_wind
    )


@kernel
def airplane_lengths_each(
    start: np.ndarray,
    heading: np.ndarray,
    ends: np.ndarray,
    radius: np.ndarray,
    tan_climb: np.ndarray,
    tan_descent: np.ndarray,
    run_in: float,
    run_out: float,
    airspeed: np.ndarray,
    wind: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``airplane_lengths`` with the radius and limits of each leg (a per-leg envelope,
    ``airplane.LegEnvelope``; every radius > 0). With a design ``wind`` from a stated direction
    ((east, north) m/s it blows towards; zeros: none) each leg may climb as steeply as the
    fastest ground speed along its own track allows (``airplane.track_factor``; ``airspeed``
    the TAS its limits were taken at); the limits given are those from any direction."""
    m = ends.shape[0]
    length = np.empty(m)
    head = np.empty((m, 3))
    norm = math.hypot(heading[0], heading[1])
    ux = heading[0] / norm
    uy = heading[1] / norm
    sx = start[0] + run_out * ux
    sy = start[1] + run_out * uy
    for i in range(m):
        wx = ends[i, 0] - sx
        wy = ends[i, 1] - sy
        r = radius[i]
        reachable, horizontal, hx, hy, hz, phi, nx, ny, _ = cs_arc(ux, uy, 0.0, wx, wy, 0.0, r)
        if reachable and run_in > 0.0:
            # the tangent's length as airplane.tangent_lengths computes it
            a = wx * ux + wy * uy
            b = abs(ux * wy - uy * wx)
            reachable = math.sqrt(max(a * a + b * (b - 2.0 * r), 0.0)) >= run_in
        if not reachable:
            length[i] = math.inf
            head[i, 0], head[i, 1], head[i, 2] = np.nan, np.nan, np.nan
            continue
        steeper = track_factor(ux, uy, nx, ny, phi, airspeed[i], wind[0], wind[1])
        length[i] = _flown(
            run_out + horizontal, ends[i, 2] - start[2], r, tan_climb[i], tan_descent[i], steeper
        )
        head[i, 0], head[i, 1], head[i, 2] = hx, hy, hz
    return length, head


@inner
def free_airplane_lengths(
    start: np.ndarray,
    ends: np.ndarray,
    radius: np.ndarray,
    tan_climb: np.ndarray,
    tan_descent: np.ndarray,
    run_in: float,
    airspeed: np.ndarray,
    wind: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """``airplane_legs`` with no heading (at A, when none is given): straight horizontal
    paths, helices where too steep, the heading out along the chord; inf where the chord is
    shorter than ``run_in``. Per leg as ``airplane_lengths_each``."""
    m = ends.shape[0]
    length = np.empty(m)
    head = np.empty((m, 3))
    for i in range(m):
        wx = ends[i, 0] - start[0]
        wy = ends[i, 1] - start[1]
        h = math.hypot(wx, wy)
        if h > COINCIDENT_M:
            head[i, 0], head[i, 1], head[i, 2] = wx / h, wy / h, 0.0 / h
        else:
            head[i, 0], head[i, 1], head[i, 2] = 1.0, 0.0, 0.0
        if h >= run_in:
            steeper = track_factor(
                head[i, 0], head[i, 1], 0.0, 0.0, 0.0, airspeed[i], wind[0], wind[1]
            )
            length[i] = _flown(
                h, ends[i, 2] - start[2], radius[i], tan_climb[i], tan_descent[i], steeper
            )
        else:
            length[i] = math.inf
    return length, head


@inner
def track_factor(
    ux: float, uy: float, nx: float, ny: float, phi: float, airspeed: float, wx: float, wy: float
) -> float:
    """(V + W) / the fastest ground speed over the headings from u turning towards n through
    ``phi`` (``airplane.track_factor``, the same operations): how much steeper than from any
    direction the leg may climb; 1 with no wind."""
    w = math.hypot(wx, wy)
    if w == 0.0:
        return 1.0
    fastest = _ground_speed(ux, uy, airspeed, wx, wy)
    c = math.cos(phi)
    s = math.sin(phi)
    fastest = max(fastest, _ground_speed(c * ux + s * nx, c * uy + s * ny, airspeed, wx, wy))
    # downwind within the arc: the angle from u to it, turning towards n, at most phi
    turned = math.atan2((wx * nx + wy * ny) / w, (wx * ux + wy * uy) / w)
    if turned < 0.0:
        turned += TWO_PI
    if phi > 0.0 and turned <= phi:
        fastest = airspeed + w
    return max((airspeed + w) / fastest, 1.0)


@inner
def _ground_speed(tx: float, ty: float, airspeed: float, wx: float, wy: float) -> float:
    """Ground speed along the unit track (tx, ty) at ``airspeed`` in the wind (wx, wy)."""
    along = wx * tx + wy * ty
    cross = wx * ty - wy * tx
    return along + math.sqrt(max(airspeed * airspeed - cross * cross, 0.0))


@inner
def _flown(
    horizontal: float,
    dz: float,
    radius: float,
    tan_climb: float,
    tan_descent: float,
    steeper: float = 1.0,
) -> float:
    """The flown length of a leg of ``horizontal`` metres and climb ``dz``: with the whole
    helix turns it needs where too steep (``airplane.helix_turns``); inf where it is too steep
    and ``radius`` is 0. The leg flies without a helix where it is no steeper than the limit
    times ``steeper`` (its track's own); a helix flies every heading, so its turns are counted
    at the limit from any direction."""
    g = tan_climb if dz > 0 else tan_descent
    need = 0.0 if math.isinf(g) else abs(dz) / g
    k = 0.0
    if need / steeper - horizontal > STEEP_SLACK_M:
        if radius <= 0.0:
            return math.inf
        k = max(math.ceil((need - horizontal - STEEP_SLACK_M) / (TWO_PI * radius)), 0.0)
    flat = horizontal + TWO_PI * radius * k
    return math.sqrt(flat * flat + dz * dz)
