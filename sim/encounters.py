"""Where a path meets the landmark database: the closest approach to a point, the correction
points passed within the capture radius (3D) in flight order, and the landmarks of the mission
(a waypoint on them) that the flown track did not pass within it of."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from gcs_planner.sim import flight_kernel
from gcs_planner.sim.replay_records import Encounter, FlightPath, Missed
from scipy.spatial import cKDTree

from gcs_planner.aircraft.profile import DEFAULT_CAPTURE_RADIUS_M
from gcs_planner.scenario.model import Kind, Scenario


def _segment_distances(
    path: FlightPath, point: np.ndarray, segs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(miss, t) of ``point`` to the path's segments ``segs`` (index of their first point)."""
    p = path.points[segs]
    d = path.points[segs + 1] - p
    len2 = np.einsum("ij,ij->i", d, d)
    rel = point - p
    t = np.where(len2 > 0, np.einsum("ij,ij->i", rel, d) / np.where(len2 > 0, len2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(rel - t[:, None] * d, axis=1), t


def _first_pass(
    path: FlightPath, point: np.ndarray, segs: np.ndarray, radius: float
) -> tuple[float, float] | None:
    """(distance flown, miss) at the closest approach of the first pass within ``radius`` of
    ``point`` over the candidate segments ``segs`` (sorted), or None."""
    miss, t = _segment_distances(path, point, segs)
    inside = np.flatnonzero(miss <= radius)
    if inside.size == 0:
        return None
    first = inside[0]
    # The pass: consecutive segments from the first one inside.
    run = first
    while run + 1 < len(segs) and segs[run + 1] == segs[run] + 1 and miss[run + 1] <= radius:
        run += 1
    j = first + int(np.argmin(miss[first : run + 1]))
    k = int(segs[j])
    cum = path.cumulative
    return float(cum[k] + t[j] * (cum[k + 1] - cum[k])), float(miss[j])


def closest_approach(
    path: FlightPath, point: np.ndarray, radius: float, *, compiled: bool = False
) -> tuple[float, float]:
    """(distance flown, 3D miss) where the path first passes within ``radius`` of ``point``,
    at the closest approach of that pass; else at its closest approach overall. ``compiled``:
    the same in sim/flight_kernel.py (a flown track has tens of thousands of segments)."""
    point = np.asarray(point, float)
    if len(path.points) < 2:
        return 0.0, float(np.linalg.norm(path.points[0] - point))
    if compiled:
        points = path.contiguous_points
        d, miss = flight_kernel.closest_approach(
            points, path.cumulative, point, float(radius), path.blocks
        )
        return float(d), float(miss)
    segs = np.arange(len(path.points) - 1)
    hit = _first_pass(path, point, segs, radius)
    if hit is not None:
        return hit
    miss, t = _segment_distances(path, point, segs)
    j = int(np.argmin(miss))
    cum = path.cumulative
    return float(cum[j] + t[j] * (cum[j + 1] - cum[j])), float(miss[j])


def find_encounters(
    path: FlightPath, scenario: Scenario, capture_radius: float = DEFAULT_CAPTURE_RADIUS_M
) -> list[Encounter]:
    """Correction points the path passes within ``capture_radius`` (3D) of, in flight order,
    each at the closest approach of its first pass (a landmark is used at most once)."""
    mask = (scenario.kind == Kind.V) | (scenario.kind == Kind.H)
    idx = np.flatnonzero(mask)
    if len(path.points) < 2 or idx.size == 0:
        return []
    seg_len = np.linalg.norm(np.diff(path.points, axis=0), axis=1)
    # A landmark within the radius of a segment is within radius + half its length of one of
    # the segment's ends.
    tree = cKDTree(path.points)
    reach = capture_radius + float(seg_len.max()) / 2 + 1e-6
    near = tree.query_ball_point(scenario.xyz[idx], r=reach)
    last = len(path.points) - 2
    out: list[Encounter] = []
    for j, pts in enumerate(near):
        if not pts:
            continue
        pts_arr = np.asarray(pts)
        segs = np.unique(np.clip(np.concatenate([pts_arr - 1, pts_arr]), 0, last))
        li = int(idx[j])
        hit = _first_pass(path, scenario.xyz[li], segs, capture_radius)
        if hit is None:
            continue
        distance, miss = hit
        k = min(int(np.searchsorted(path.cumulative, distance, side="right")), len(path.seqs) - 1)
        out.append(
            Encounter(
                li,
                scenario.ids[li],
                Kind(int(scenario.kind[li])),
                bool(scenario.unreliable[li]),
                distance,
                miss,
                int(path.seqs[k]),
            )
        )
    out.sort(key=lambda e: e.distance)
    return out


def mission_landmarks(
    nominal: FlightPath, scenario: Scenario, capture_radius: float = DEFAULT_CAPTURE_RADIUS_M
) -> list[tuple[int, int]]:
    """(landmark, seq) of the correction landmarks the mission has a waypoint on (within
    ``capture_radius``), in mission order, each once."""
    mask = (scenario.kind == Kind.V) | (scenario.kind == Kind.H)
    idx = np.flatnonzero(mask)
    if idx.size == 0 or len(nominal.points) < 2:
        return []
    tree = cKDTree(scenario.xyz[idx])
    out: list[tuple[int, int]] = []
    seen: set[int] = set()
    for p, seq in zip(nominal.points[1:], nominal.seqs[1:], strict=True):
        for j in tree.query_ball_point(p, r=capture_radius):
            li = int(idx[j])
            if li not in seen:
                seen.add(li)
                out.append((li, int(seq)))
    return out


def find_missed(
    nominal: FlightPath,
    flown: FlightPath,
    encounters: Sequence[Encounter],
    scenario: Scenario,
    capture_radius: float = DEFAULT_CAPTURE_RADIUS_M,
    *,
    compiled: bool = False,
    landmarks: Sequence[tuple[int, int]] | None = None,
) -> list[Missed]:
    """Correction landmarks the mission has a waypoint on (within ``capture_radius``) that the
    flown track did not pass within ``capture_radius`` of, in mission order (``compiled``:
    their closest approaches found by the kernel). ``landmarks``: mission_landmarks of
    ``nominal``, when the caller has them (a Monte Carlo flies one mission many times)."""
    if landmarks is None:
        landmarks = mission_landmarks(nominal, scenario, capture_radius)
    met = {e.landmark for e in encounters}
    out: list[Missed] = []
    for li, seq in landmarks:
        if li in met:
            continue
        distance, miss = closest_approach(
            flown, scenario.xyz[li], capture_radius, compiled=compiled
        )
        kind = Kind(int(scenario.kind[li])).name
        out.append(Missed(li, scenario.ids[li], kind, seq, distance, miss))
    return out
