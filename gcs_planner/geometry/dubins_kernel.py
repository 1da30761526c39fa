"""The tilted-plane CS legs (``dubins.cs_lengths``, the cs3d leg model) from a heading, compiled
(numba), for the searches that fly thousands of partial routes. The same formulas as
``dubins._core`` in the same order; sums of three products may round differently from numpy's
matrix products, so lengths and headings agree to a few ulp (tested), not bit for bit."""

from __future__ import annotations

import math

import numpy as np

from gcs_planner.geometry.dubins import COINCIDENT_M, STRAIGHT_TOL, TWO_PI
from gcs_planner.runtime.jit import inner, kernel


@inner
def cs_core(
    ux: float, uy: float, uz: float, wx: float, wy: float, wz: float, radius: float
) -> tuple[bool, float, float, float, float]:
    """One CS leg from the origin with unit heading u to the offset w, radius > 0, as
    ``dubins._core`` computes it: (reachable, length, heading at the target)."""
    reachable, length, hx, hy, hz, _, _, _, _ = cs_arc(ux, uy, uz, wx, wy, wz, radius)
    return reachable, length, hx, hy, hz


@inner
def cs_arc(
    ux: float, uy: float, uz: float, wx: float, wy: float, wz: float, radius: float
) -> tuple[bool, float, float, float, float, float, float, float, float]:
    """``cs_core`` with the arc: (reachable, length, heading at the target, arc angle phi,
    unit normal towards the turn); phi 0 on a straight leg, NaN where not reachable."""
    R = radius
    chord = math.sqrt(wx * wx + wy * wy + wz * wz)
    a = wx * ux + wy * uy + wz * uz
    cx = uy * wz - uz * wy
    cy = uz * wx - ux * wz
    cz = ux * wy - uy * wx
    b = math.sqrt(cx * cx + cy * cy + cz * cz)
    coincident = chord <= COINCIDENT_M
    on_axis = b <= STRAIGHT_TOL * chord and not coincident
    behind = on_axis and a < 0.0
    if behind:
        b = 0.0
    # The in-plane normal towards the target (two Gram-Schmidt passes, as _core).
    px = wx - a * ux
    py = wy - a * uy
    pz = wz - a * uz
    d = px * ux + py * uy + pz * uz
    px -= d * ux
    py -= d * uy
    pz -= d * uz
    pn = math.sqrt(px * px + py * py + pz * pz)
    div = pn if pn > 0.0 else 1.0
    nx, ny, nz = px / div, py / div, pz / div
    if behind:  # dubins.behind_normal: horizontal, on the left of u
        left = math.hypot(-uy, ux)
        if left < 1e-12:  # u vertical: y x u
            left = math.sqrt(uz * uz + 0.0 + ux * ux)
            nx, ny, nz = uz / left, 0.0, -ux / left
        else:
            nx, ny, nz = -uy / left, ux / left, 0.0
    t2 = a * a + b * (b - 2.0 * R)
    reachable = t2 >= 0.0 or coincident
    straight = (on_axis and a >= 0.0 and reachable) or coincident
    t = math.sqrt(max(t2, 0.0))
    if a > 0.0 and t2 >= 0.0:
        a_minus_t = b * (2.0 * R - b) / (a + t)
    else:
        a_minus_t = a - t
    phi = math.atan2(R * a_minus_t + b * t, (R - b) * R + a * t)
    if phi < 0.0:
        phi = phi + TWO_PI
    phi = phi + 0.0
    if not reachable:
        return False, math.inf, np.nan, np.nan, np.nan, np.nan, nx, ny, nz
    if straight:
        return True, chord, ux, uy, uz, 0.0, nx, ny, nz
    c = math.cos(phi)
    s = math.sin(phi)
    hx = c * ux + s * nx
    hy = c * uy + s * ny
    hz = c * uz + s * nz
    hn = math.sqrt(hx * hx + hy * hy + hz * hz)
    return True, R * phi + t, hx / hn, hy / hn, hz / hn, phi, nx, ny, nz


@kernel
def cs_lengths(
    start: np.ndarray, heading: np.ndarray, ends: np.ndarray, radius: float
) -> tuple[np.ndarray, np.ndarray]:
    """(flown lengths, headings at the targets (m, 3)) of the CS legs from ``start`` with
    ``heading`` (any non-zero 3-vector) to each row of ``ends``: inf and NaN where a target
    lies inside the turning circle."""
    m = ends.shape[0]
    length = np.empty(m)
    head = np.empty((m, 3))
    norm = math.sqrt(heading[0] * heading[0] + heading[1] * heading[1] + heading[2] * heading[2])
    ux, uy, uz = heading[0] / norm, heading[1] / norm, heading[2] / norm
    for i in range(m):
        wx = ends[i, 0] - start[0]
        wy = ends[i, 1] - start[1]
        wz = ends[i, 2] - start[2]
        if radius == 0.0:
            chord = math.sqrt(wx * wx + wy * wy + wz * wz)
            length[i] = chord
            if chord > COINCIDENT_M:
                head[i, 0], head[i, 1], head[i, 2] = wx / chord, wy / chord, wz / chord
            else:
                head[i, 0], head[i, 1], head[i, 2] = ux, uy, uz
            continue
        _, length[i], head[i, 0], head[i, 1], head[i, 2] = cs_core(ux, uy, uz, wx, wy, wz, radius)
    return length, head
