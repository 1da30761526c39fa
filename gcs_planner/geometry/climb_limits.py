"""How steep a leg may climb or descend, and what follows for its shape: the horizontal path
a change of altitude needs, the whole helix turns that give it, and the heading-free lower bound
of a leg under the limits (docs/model.md, "Airplane legs")."""

from __future__ import annotations

import math

import numpy as np

from gcs_planner.geometry.dubins import TWO_PI

# Rounding slack on "steep enough for a helix": a leg needing 1e-9 m more horizontal path than it
# has is flown without one (the difference is far below anything an aircraft can fly).
STEEP_SLACK_M = 1e-9


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
