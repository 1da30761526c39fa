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
from gcs_planner.geometry.dubins_kernel import cs_core
from gcs_planner.jit import inner, kernel


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
    if radius <= 0.0:
        return free_airplane_lengths(start, ends, radius, tan_climb, tan_descent, 0.0)
    m = ends.shape[0]
    return airplane_lengths_each(
        start, heading, ends, np.full(m, radius), np.full(m, tan_climb),
        np.full(m, tan_descent), run_in, run_out,
    )  # fmt: skip


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
) -> tuple[np.ndarray, np.ndarray]:
    """``airplane_lengths`` with the radius and limits of each leg (a per-leg envelope,
    ``airplane.LegEnvelope``; every radius > 0)."""
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
        reachable, horizontal, hx, hy, hz = cs_core(ux, uy, 0.0, wx, wy, 0.0, r)
        if reachable and run_in > 0.0:
            # the tangent's length as airplane.tangent_lengths computes it
            a = wx * ux + wy * uy
            b = abs(ux * wy - uy * wx)
            reachable = math.sqrt(max(a * a + b * (b - 2.0 * r), 0.0)) >= run_in
        if not reachable:
            length[i] = math.inf
            head[i, 0], head[i, 1], head[i, 2] = np.nan, np.nan, np.nan
            continue
        length[i] = _flown(
            run_out + horizontal, ends[i, 2] - start[2], r, tan_climb[i], tan_descent[i]
        )
        head[i, 0], head[i, 1], head[i, 2] = hx, hy, hz
    return length, head


@inner
def free_airplane_lengths(
    start: np.ndarray,
    ends: np.ndarray,
    radius: float,
    tan_climb: float,
    tan_descent: float,
    run_in: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """``airplane_legs`` with no heading (at A, when none is given): straight horizontal
    paths, helices where too steep, the heading out along the chord; inf where the chord is
    shorter than ``run_in``."""
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
            length[i] = _flown(h, ends[i, 2] - start[2], radius, tan_climb, tan_descent)
        else:
            length[i] = math.inf
    return length, head


@inner
def _flown(
    horizontal: float, dz: float, radius: float, tan_climb: float, tan_descent: float
) -> float:
    """The flown length of a leg of ``horizontal`` metres and climb ``dz``: with the whole
    helix turns it needs where too steep (``airplane.helix_turns``); inf where it is too steep
    and ``radius`` is 0."""
    g = tan_climb if dz > 0 else tan_descent
    need = 0.0 if math.isinf(g) else abs(dz) / g
    k = 0.0
    if need - horizontal > STEEP_SLACK_M:
        if radius <= 0.0:
            return math.inf
        k = max(math.ceil((need - horizontal - STEEP_SLACK_M) / (TWO_PI * radius)), 0.0)
    flat = horizontal + TWO_PI * radius * k
    return math.sqrt(flat * flat + dz * dz)
