"""What the pictures of a plan share: their colours and units, the PNG they are saved as (headless,
matplotlib's Agg backend, chosen here before pyplot is imported), the plan's points and route
stops, the title of a route, and the route's points labelled with their ids on any view."""

from __future__ import annotations

import io
from collections.abc import Sequence
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from gcs_planner.mission.picture_labels import (  # noqa: E402
    Label,
    LabelPlacer,
    left_out,
    marker_radius,
)

__all__ = ["plt"]  # pyplot as the pictures use it: on the Agg backend

LIMIT = "#d62728"
MARGIN = "#2ca02c"
COLOURS = {"V": "#1f77b4", "H": "#ff7f0e", "A": "#2ca02c", "B": "#d62728", "track": "#222222"}
UNRELIABLE = "#d62728"
KM = 1000.0
DPI = 110
CHROME = 1.8  # inches of a picture's title and legend


def to_png(fig: Figure) -> bytes:
    """``fig`` as PNG bytes; the figure is closed."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    plt.close(fig)
    return buf.getvalue()


def plan_points(plan: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(n, 3) positions, kinds and unreliable flags of every point of the plan."""
    pts = plan.get("points") or []
    xyz = np.array([[p["x"], p["y"], p["z"]] for p in pts], dtype=float).reshape(-1, 3)
    kind = np.array([str(p.get("kind", "")) for p in pts])
    unreliable = np.array([bool(p.get("unreliable", False)) for p in pts], dtype=bool)
    return xyz, kind, unreliable


def scatter_points(ax: Axes, pts: np.ndarray, dims: tuple[int, ...], **kw: Any) -> None:
    """Scatter rows of ``pts`` (or one point) on the axes ``dims``; no depth shading in 3D,
    which would make far points look like a different colour."""
    pts = np.atleast_2d(pts)
    if len(dims) == 3:
        kw["depthshade"] = False
    ax.scatter(*(pts[:, d] for d in dims), **kw)


def route_title(plan: dict, k: int, entry: dict) -> str:
    """The title of route ``k`` (``entry``, of the plan's front): its length, corrections,
    probability and turning radius."""
    scen = plan.get("scenario") or {}
    name = scen.get("name", "scenario")
    parts = [f"{name}: route {k}", f"{entry.get('length', float('nan')) / KM:.2f} km flown"]
    parts.append(f"{entry.get('corrections', len(entry['route']) - 2)} corrections")
    if "probability" in (plan.get("objectives") or []):
        parts.append(f"P(success) {entry.get('probability', float('nan')):.3f}")
    radius = (plan.get("parameters") or {}).get("turn_radius")
    if radius is not None:
        parts.append(f"turn radius {radius:g} m")
    return ", ".join(parts)


def flown_distance(track: np.ndarray) -> np.ndarray:
    """Distance flown (same unit as ``track``) at each vertex of the flown polyline."""
    steps = np.linalg.norm(np.diff(track, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def route_stops(entry: dict) -> tuple[list[str], np.ndarray]:
    """Ids of the route's points and the distance flown (m) at each, A first."""
    ids = [str(pid) for pid in entry["route"]]
    along = [0.0] + [float(leg.get("cumulative", np.nan)) for leg in entry["legs"]]
    return ids, np.asarray(along, dtype=float)


# Marker areas (points²) of the route's points, A and B.
ROUTE_SIZE, A_SIZE, B_SIZE = 70.0, 300.0, 150.0
RING_SIZE = 220.0  # the ring round an unreliable point of the route


def route_labels(
    pts: np.ndarray,
    ids: list[str],
    sizes: tuple[float, float, float] = (ROUTE_SIZE, A_SIZE, B_SIZE),
) -> list[Label]:
    """The route points' id labels: A and B first and in bold, then every other point, then
    the rest (so that, short of room, the labels left out are spread along the route)."""
    labels = []
    last = len(ids) - 1
    for n, pid in enumerate(ids):
        end = n in (0, last)
        size = sizes[1] if n == 0 else sizes[2] if n == last else sizes[0]
        labels.append(
            Label(
                pid,
                tuple(pts[n]),
                priority=0 if end else 1 + n % 2,
                size=12 if end else 8.5,
                weight="bold" if end else "normal",
                colour="black" if end else "0.2",
                clearance=marker_radius(size),
            )
        )
    return labels


def label_route(
    placer: LabelPlacer,
    ax: Axes,
    pts: np.ndarray,
    ids: list[str],
    lines: Sequence[np.ndarray] = (),
    sizes: tuple[float, float, float] = (ROUTE_SIZE, A_SIZE, B_SIZE),
    ringed: np.ndarray | None = None,
) -> None:
    """Label the route's points with their ids, clear of their markers (and of the rings
    round the ``ringed`` ones, unreliable) and of ``lines``."""
    labels = route_labels(pts, ids, sizes)
    markers = [(pts, marker_radius(sizes[0])), (pts[:1], marker_radius(sizes[1]))]
    markers.append((pts[-1:], marker_radius(sizes[2])))
    if ringed is not None and ringed.any():
        markers.append((pts[ringed], marker_radius(RING_SIZE)))
        for lab, ring in zip(labels, ringed, strict=True):
            if ring:
                lab.clearance = max(lab.clearance, marker_radius(RING_SIZE))
    left_out(ax, placer.place(ax, labels, markers, lines), "id")


def route_kinds(plan: dict, entry: dict) -> np.ndarray:
    """Kind letter of each route point, A first."""
    kinds = ["A"] + [str(leg.get("kind", "")) for leg in entry["legs"]]
    kinds[-1] = "B"
    return np.array(kinds)
