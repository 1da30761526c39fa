"""The route picture: the route over all correction points, its plan view (XOY) and side view,
with a 3D view as in the paper's Figure 8 only where it can be read (at most
``THREE_D_MAX_POINTS`` points; a cloud of thousands of points hides the route in 3D)."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.map_view import MapView
from gcs_planner.mission.picture_axes import (
    A_SIZE,
    B_SIZE,
    CHROME,
    COLOURS,
    DPI,
    KM,
    RING_SIZE,
    ROUTE_SIZE,
    UNRELIABLE,
    label_route,
    plan_points,
    plt,
    route_kinds,
    route_stops,
    route_title,
    scatter_points,
    to_png,
)
from gcs_planner.mission.picture_labels import LabelPlacer
from gcs_planner.mission.plan_reading import route_entry, route_legs, route_xyz
from gcs_planner.mission.profile_view import draw_side_view, label_side_view

# A 3D view is drawn only up to this many points: beyond, the cloud hides the route.
THREE_D_MAX_POINTS = 1000
# Beyond this many points the points off the route are drawn as a faint background.
DENSE_POINTS = 2000

FIG_W = 15.0  # inches, the route picture
SIDE_H = 3.4  # inches, the side view below the maps


def _route_layout(aspect: float, with3d: bool) -> tuple[Figure, Axes | None, Axes, Axes]:
    """Figure and axes of the route picture, sized so that the plan view (``aspect``: its
    height over width as drawn) fills its slot: with a 3D view, the 3D and plan views above the
    side view; without, the plan view above the side view when it is flat, beside it when not."""
    if with3d or aspect < 0.5:
        room = FIG_W - (5.5 if with3d else 0.0) - 1.0
        top = float(np.clip(room * aspect, 4.4 if with3d else 2.0, 5.4))
        plan_w = min(room, top / aspect) + 1.0
        fig = plt.figure(figsize=(FIG_W, top + SIDE_H + CHROME), layout="constrained", dpi=DPI)
        if with3d:
            # A spacer column: the layout engine does not see the 3D view's z label.
            grid = fig.add_gridspec(
                2,
                3,
                width_ratios=[FIG_W - plan_w - 0.4, 0.4, plan_w],
                height_ratios=[top, SIDE_H],
            )
            ax3 = fig.add_subplot(grid[0, 0], projection="3d")
            axy = fig.add_subplot(grid[0, 2])
        else:
            grid = fig.add_gridspec(2, 1, height_ratios=[top + 0.6, SIDE_H])
            ax3, axy = None, fig.add_subplot(grid[0, 0])
        axz = fig.add_subplot(grid[1, :])
        return fig, ax3, axy, axz
    height = 7.6
    plan_w = float(np.clip((height - CHROME - 0.6) / aspect, 4.0, 8.5)) + 1.0
    fig = plt.figure(figsize=(FIG_W, height), layout="constrained", dpi=DPI)
    grid = fig.add_gridspec(1, 2, width_ratios=[plan_w, FIG_W - plan_w])
    return fig, None, fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1])


def _point_layers(
    kind: np.ndarray, unreliable: np.ndarray, visited: np.ndarray, dense: bool
) -> list[tuple[np.ndarray, dict]]:
    """(selection, scatter style) of the plan's points, in drawing order: the points off the
    route faint, the route's own with their markers, the unreliable ones ringed (crossed off
    the route, unless thousands of crosses would hide it)."""
    faint = {"s": 2, "alpha": 0.2, "lw": 0} if dense else {"s": 9, "alpha": 0.35}
    layers = [
        ((kind == "V") & ~visited, {"c": COLOURS["V"], "marker": "o", **faint}),
        ((kind == "H") & ~visited, {"c": COLOURS["H"], "marker": "^", **faint}),
        ((kind == "V") & visited, {"s": ROUTE_SIZE, "c": COLOURS["V"], "marker": "o", "ec": "k"}),
        ((kind == "H") & visited, {"s": ROUTE_SIZE, "c": COLOURS["H"], "marker": "^", "ec": "k"}),
        (unreliable & visited, {"s": RING_SIZE, "fc": "none", "ec": UNRELIABLE, "lw": 1.6}),
    ]
    if not dense:  # thousands of crosses would hide the route
        off = {"s": 14, "c": UNRELIABLE, "marker": "x", "lw": 0.6, "alpha": 0.6}
        layers.insert(2, (unreliable & ~visited, off))
    return layers


def _dress_3d_view(ax3: Axes) -> None:
    """The 3D view's axes, title and viewpoint."""
    ax3.set_xlabel("x east (km)")
    ax3.set_ylabel("y north (km)")
    ax3.set_zlabel("z up (km)")
    ax3.set_title("3D view")
    ax3.view_init(elev=24, azim=-60)
    ax3.set_box_aspect((5, 4, 3))  # wider than deep: its slot is wide


def route_figure(plan: dict, route_index: int | None = None) -> Figure:
    """The route over all correction points: plan view and side view (altitude against distance
    flown), and a 3D view for scenarios of at most ``THREE_D_MAX_POINTS`` points; the route's
    points labelled with their ids, no label over another."""
    k, entry = route_entry(plan, route_index)
    legs = route_legs(entry)
    route_m = route_xyz(plan, entry, legs)
    route = route_m / KM
    track_m = trajectory_local(plan, k)
    track = track_m / KM
    xyz, kind, unreliable = plan_points(plan)
    xyz = xyz / KM
    route_ids, along = route_stops(entry)
    on_route = set(route_ids)
    ids = [str(p.get("id")) for p in plan.get("points") or []]
    visited = np.array([pid in on_route for pid in ids], dtype=bool)
    kinds = route_kinds(plan, entry)
    with3d = len(xyz) <= THREE_D_MAX_POINTS
    dense = len(xyz) > DENSE_POINTS

    view = MapView.of(np.r_[xyz[:, 0], track[:, 0]], np.r_[xyz[:, 1], track[:, 1]])
    fig, ax3, axy, axz = _route_layout(view.aspect, with3d)

    layers = _point_layers(kind, unreliable, visited, dense)
    for ax, dims in ((ax3, (0, 1, 2)), (axy, (0, 1))):
        if ax is None:
            continue
        for sel, style in layers:
            if sel.any():
                scatter_points(ax, xyz[sel], dims, **style)
        ax.plot(*(track[:, d] for d in dims), color=COLOURS["track"], lw=1.6, zorder=3)
        scatter_points(ax, route[0], dims, s=A_SIZE, c=COLOURS["A"], marker="*", ec="k", zorder=5)
        scatter_points(ax, route[-1], dims, s=B_SIZE, c=COLOURS["B"], marker="s", ec="k", zorder=5)
    helices = draw_side_view(axz, track_m, along, route_m, route_ids, kinds, entry)
    axz.set_xlabel("distance flown (km)")
    view.apply(axy, "plan view")
    if ax3 is not None:
        _dress_3d_view(ax3)

    fig.legend(
        handles=_legend(dense), loc="outside lower center", ncol=4, fontsize=10, frameon=False
    )
    fig.suptitle(route_title(plan, k, entry), fontsize=14)
    placer = LabelPlacer(fig)
    ringed = np.array([False] + [bool(leg.get("unreliable", False)) for leg in entry["legs"]])
    label_route(placer, axy, route[:, :2], route_ids, [track[:, :2]], ringed=ringed)
    label_side_view(placer, axz, track_m, along, route_m, route_ids, helices)
    if ax3 is not None:
        label_route(placer, ax3, route, route_ids, [track], ringed=ringed)
    return fig


def route_png(plan: dict, route_index: int | None = None) -> bytes:
    """``route_figure`` as PNG bytes."""
    return to_png(route_figure(plan, route_index))


def _legend(dense: bool = False) -> list[Line2D]:
    """The route picture's legend (``dense``: the points off the route drawn smaller)."""

    def marker(label: str, **kw) -> Line2D:
        return Line2D([], [], ls="", label=label, **kw)

    other = {"ms": 2.5, "alpha": 0.5} if dense else {"ms": 4, "alpha": 0.5}
    return [
        Line2D([], [], color=COLOURS["track"], lw=1.6, label="flown trajectory (arcs + straights)"),
        marker(
            "V point (vertical correction) on route",
            marker="o",
            ms=8,
            mfc=COLOURS["V"],
            mec="black",
        ),
        marker(
            "H point (horizontal correction) on route",
            marker="^",
            ms=8,
            mfc=COLOURS["H"],
            mec="black",
        ),
        marker("other V points", marker="o", mfc=COLOURS["V"], mec="none", **other),
        marker("other H points", marker="^", mfc=COLOURS["H"], mec="none", **other),
        marker(
            "unreliable correction point on route"
            if dense
            else "unreliable correction point (x when off route)",
            marker="o",
            ms=13,
            mfc="none",
            mec=UNRELIABLE,
            mew=1.6,
        ),
        marker("A (start)", marker="*", ms=15, mfc=COLOURS["A"], mec="black"),
        marker("B (end)", marker="s", ms=10, mfc=COLOURS["B"], mec="black"),
    ]
