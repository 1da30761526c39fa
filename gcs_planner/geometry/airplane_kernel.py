"""Airplane legs from a heading, compiled (numba): ``airplane.airplane_legs`` for searches that
fly thousands of partial routes (the branch and bound with turns asks it once per label, for a
dozen targets, where numpy's cost per call is most of the time).

The same formulas in the same order as ``dubins._core`` in the horizontal plane and
``airplane.airplane_legs`` (the helix turns and the flown length); only the sums of three
products may round differently (numpy's matrix product may fuse them), so lengths and headings
agree to a few ulp (tested), not bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from gcs_planner.geometry.airplane import STEEP_SLACK_M
from gcs_planner.geometry.dubins import COINCIDENT_M, STRAIGHT_TOL, TWO_PI


@njit(cache=True)
def airplane_lengths(
    start: np.ndarray,
    heading: np.ndarray,
    ends: np.ndarray,
    radius: float,
    tan_climb: float,
    tan_descent: float,
) -> tuple[np.ndarray, np.ndarray]:
    """(flown lengths, horizontal headings at the targets (m, 3)) of the airplane legs from
    ``start`` with horizontal ``heading`` to each row of ``ends``; inf and NaN where a target
    lies inside the turning circle. ``radius`` > 0; tangents inf for limits of 90 degrees."""
    m = ends.shape[0]
    length = np.empty(m)
    head = np.empty((m, 3))
    norm = math.hypot(heading[0], heading[1])
    ux = heading[0] / norm
    uy = heading[1] / norm
    R = radius
    for i in range(m):
        wx = ends[i, 0] - start[0]
        wy = ends[i, 1] - start[1]
        chord = math.sqrt(wx * wx + wy * wy + 0.0 * 0.0)
        a = wx * ux + wy * uy + 0.0 * 0.0
        cz = ux * wy - uy * wx
        b = math.sqrt(0.0 + 0.0 + cz * cz)
        coincident = chord <= COINCIDENT_M
        on_axis = b <= STRAIGHT_TOL * chord and not coincident
        behind = on_axis and a < 0.0
        if behind:
            b = 0.0
        # The in-plane normal towards the target (two Gram-Schmidt passes, as _core).
        px = wx - a * ux
        py = wy - a * uy
        pz = 0.0 - a * 0.0
        d = px * ux + py * uy + pz * 0.0
        px -= d * ux
        py -= d * uy
        pz -= d * 0.0
        pn = math.sqrt(px * px + py * py + pz * pz)
        div = pn if pn > 0.0 else 1.0
        nx, ny, nz = px / div, py / div, pz / div
        if behind:  # straight behind: the horizontal normal on the left of u
            left = math.hypot(-uy, ux)
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
        if straight:
            phi = 0.0
            t = chord
        if straight:
            hx, hy, hz = ux, uy, 0.0
        else:
            c = math.cos(phi)
            s = math.sin(phi)
            hx = c * ux + s * nx
            hy = c * uy + s * ny
            hz = c * 0.0 + s * nz
            hn = math.sqrt(hx * hx + hy * hy + hz * hz)
            hx, hy, hz = hx / hn, hy / hn, hz / hn
        horizontal = chord if straight else R * phi + t
        if not reachable:
            length[i] = math.inf
            head[i, 0] = head[i, 1] = head[i, 2] = np.nan
            continue
        # Helix turns where the leg is too steep for its horizontal path.
        dz = ends[i, 2] - start[2]
        g = tan_climb if dz > 0 else tan_descent
        need = 0.0 if math.isinf(g) else abs(dz) / g
        k = 0.0
        if need - horizontal > STEEP_SLACK_M:
            k = max(math.ceil((need - horizontal - STEEP_SLACK_M) / (TWO_PI * R)), 0.0)
        flat = horizontal + TWO_PI * R * k
        length[i] = math.sqrt(flat * flat + dz * dz)
        head[i, 0], head[i, 1], head[i, 2] = hx, hy, hz
    return length, head
