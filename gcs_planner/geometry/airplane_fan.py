"""The airplane legs from one start and heading to many targets at once (``airplane_legs``):
the lengths, headings and helix turns of a whole fan of legs, as the search flies them. One leg
with its geometry is ``airplane.airplane_leg``; the model is in ``airplane``'s docstring."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gcs_planner.geometry.climb_limits import helix_turns, needed_horizontal_tan, slope_tan
from gcs_planner.geometry.dubins import COINCIDENT_M, TWO_PI, _core
from gcs_planner.geometry.leg_envelope import LegEnvelope, track_factor


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
