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
from numba import njit

from gcs_planner.geometry.airplane import STEEP_SLACK_M
from gcs_planner.geometry.dubins import TWO_PI
from gcs_planner.geometry.dubins_kernel import cs_core


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
    for i in range(m):
        wx = ends[i, 0] - start[0]
        wy = ends[i, 1] - start[1]
        reachable, horizontal, hx, hy, hz = cs_core(ux, uy, 0.0, wx, wy, 0.0, radius)
        if not reachable:
            length[i] = math.inf
            head[i, 0], head[i, 1], head[i, 2] = np.nan, np.nan, np.nan
            continue
        # Helix turns where the leg is too steep for its horizontal path.
        dz = ends[i, 2] - start[2]
        g = tan_climb if dz > 0 else tan_descent
        need = 0.0 if math.isinf(g) else abs(dz) / g
        k = 0.0
        if need - horizontal > STEEP_SLACK_M:
            k = max(math.ceil((need - horizontal - STEEP_SLACK_M) / (TWO_PI * radius)), 0.0)
        flat = horizontal + TWO_PI * radius * k
        length[i] = math.sqrt(flat * flat + dz * dz)
        head[i, 0], head[i, 1], head[i, 2] = hx, hy, hz
    return length, head
