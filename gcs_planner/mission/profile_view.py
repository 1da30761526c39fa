"""The side view of a route: altitude against distance flown, from the flown polyline, with the
route's points, its helices named beside their legs, and their labels."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes

from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.picture_axes import (
    COLOURS,
    KM,
    flown_distance,
    route_labels,
)
from gcs_planner.mission.picture_labels import Label, LabelPlacer, left_out, marker_radius

# Marker areas (points²) of the side view's route points, A and B.
SIDE_SIZE, SIDE_A, SIDE_B = 40.0, 200.0, 90.0


def side_profile(plan: dict, route_index: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(distance flown in metres, altitude z in metres) along the route's flown polyline: the
    side view an operator reads climbs, descents and helices from."""
    track = trajectory_local(plan, route_index)
    return flown_distance(track), track[:, 2]


def draw_side_view(
    ax: Axes,
    track: np.ndarray,
    stops_along: np.ndarray,
    route: np.ndarray,
    ids: list[str],
    kinds: np.ndarray,
    entry: dict,
) -> list[Label]:
    """Altitude against distance flown, from the flown polyline: climbs, descents and helices
    appear as flown (a helix keeps the leg's constant path angle, so it is named beside it).
    Returns the view's labels beyond the route's ids (the helices), to place once drawn."""
    along = flown_distance(track)
    ax.plot(along / KM, track[:, 2], color=COLOURS["track"], lw=1.4)
    labels = []
    for n, leg in enumerate(entry["legs"]):
        turns = int(leg.get("helix_turns", 0) or 0)
        if turns:
            labels.append(
                Label(
                    f"helix: {turns} turn{'s' if turns > 1 else ''}",
                    (
                        (stops_along[n] + stops_along[n + 1]) / 2 / KM,
                        (route[n, 2] + route[n + 1, 2]) / 2,
                    ),
                    priority=1,
                    size=9,
                    weight="bold",
                    colour="#9467bd",
                    clearance=1.0,
                    directions=((1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1)),
                )
            )
    for k in ("V", "H"):
        sel = kinds == k
        ax.scatter(
            stops_along[sel] / KM,
            route[sel, 2],
            s=SIDE_SIZE,
            c=COLOURS[k],
            marker="o" if k == "V" else "^",
            edgecolors="black",
            zorder=3,
        )
    ax.scatter(
        stops_along[0] / KM, route[0, 2], s=SIDE_A, c=COLOURS["A"], marker="*", ec="k", zorder=4
    )
    ax.scatter(
        stops_along[-1] / KM, route[-1, 2], s=SIDE_B, c=COLOURS["B"], marker="s", ec="k", zorder=4
    )
    ax.set_ylabel("altitude z (m)")
    ax.set_title("side view: altitude against distance flown")
    ax.margins(x=0.03, y=0.15)
    ax.grid(True, alpha=0.3)
    return labels


def label_side_view(
    placer: LabelPlacer,
    ax: Axes,
    track_m: np.ndarray,
    along: np.ndarray,
    route_m: np.ndarray,
    ids: list[str],
    extra: list[Label],
) -> None:
    """The side view's labels: the route's ids and the helices, clear of the profile."""
    pts = np.column_stack([along / KM, route_m[:, 2]])
    profile = np.column_stack([flown_distance(track_m) / KM, track_m[:, 2]])
    labels = route_labels(pts, ids, (SIDE_SIZE, SIDE_A, SIDE_B)) + extra
    markers = [(pts, marker_radius(SIDE_SIZE)), (pts[:1], marker_radius(SIDE_A))]
    markers.append((pts[-1:], marker_radius(SIDE_B)))
    left_out(ax, placer.place(ax, labels, markers, [profile]))
