"""The error budget picture, what an operator checks before flying: the vertical and horizontal
error against distance flown (the sawtooth of corrections), each point's limits and the margin
left at it, beside the plan view and the side view (altitude against distance flown)."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.map_view import MapView
from gcs_planner.mission.picture_axes import (
    CHROME,
    COLOURS,
    DPI,
    KM,
    LIMIT,
    MARGIN,
    RING_SIZE,
    UNRELIABLE,
    label_route,
    plt,
    route_kinds,
    route_stops,
    route_title,
    to_png,
)
from gcs_planner.mission.picture_labels import ABOVE, Label, LabelPlacer, left_out, marker_radius
from gcs_planner.mission.plan_reading import route_entry, route_legs, route_xyz
from gcs_planner.mission.profile_view import draw_side_view, label_side_view


def sawtooth(entry: dict, component: str, resets: str) -> tuple[np.ndarray, np.ndarray]:
    """(distance flown in metres, error in units) of one error component along a front entry,
    corrections succeeding: it grows along each leg to the arrival error the plan states and
    drops to 0 at each point of kind ``resets`` ("V" for the vertical error, "H" for the
    horizontal one)."""
    legs = entry["legs"]
    along = np.array([0.0] + [float(leg["cumulative"]) for leg in legs])
    arrival = np.array([0.0] + [float(leg[f"{component}_error"]) for leg in legs])
    kinds = np.array(["A"] + [str(leg.get("kind", "")) for leg in legs])
    after = np.where(kinds == resets, 0.0, arrival)
    after[0] = 0.0
    # (s_i, after_i) -> (s_i+1, arrival_i+1), then the drop to after_i+1
    return np.repeat(along, 2)[1:], np.column_stack([arrival, after]).ravel()[1:]


BUDGET_W = 16.0  # inches, the error budget picture
BUDGET_ROW = 2.5  # inches, each of its side view and error plots when the plan view is above


def _budget_layout(aspect: float) -> tuple[Figure, Axes, Axes, Axes, Axes]:
    """Figure and axes (plan, side, vertical, horizontal) of the error budget: the plan view
    (``aspect``: its height over width as drawn) left of the three others when it is tall
    enough, above them when it is flat."""
    if aspect >= 0.6:
        height = 10.0
        left = float(np.clip((height - CHROME - 0.6) / aspect, 4.0, 8.0)) + 1.0
        fig = plt.figure(figsize=(BUDGET_W, height), layout="constrained", dpi=DPI)
        grid = fig.add_gridspec(3, 2, width_ratios=[left, BUDGET_W - left])
        axy = fig.add_subplot(grid[:, 0])
        right = [grid[n, 1] for n in range(3)]
    else:
        top = float(np.clip((BUDGET_W - 1.0) * aspect, 1.5, 4.5)) + 0.6
        fig = plt.figure(
            figsize=(BUDGET_W, top + 3 * BUDGET_ROW + CHROME), layout="constrained", dpi=DPI
        )
        grid = fig.add_gridspec(4, 1, height_ratios=[top] + [BUDGET_ROW] * 3)
        axy = fig.add_subplot(grid[0, 0])
        right = [grid[n, 0] for n in range(1, 4)]
    axz = fig.add_subplot(right[0])
    axv = fig.add_subplot(right[1], sharex=axz)
    axh = fig.add_subplot(right[2], sharex=axz)
    return fig, axy, axz, axv, axh


# Marker areas (points²) of the error budget's plan view: route points, A and B.
BUDGET_SIZES = (50.0, 260.0, 120.0)


def error_budget_figure(plan: dict, route_index: int | None = None) -> Figure:
    """The error budget of a route: vertical and horizontal error against distance flown, with
    each point's limits and the margin left on arrival, beside the plan and side views."""
    k, entry = route_entry(plan, route_index)
    legs = route_legs(entry)
    route_m = route_xyz(plan, entry, legs)
    track_m = trajectory_local(plan, k)
    ids, along = route_stops(entry)
    kinds = route_kinds(plan, entry)
    params = plan.get("parameters") or {}
    residual = float(params.get("fail_residual", 0.0))
    unreliable = [False] + [bool(leg.get("unreliable", False)) for leg in entry["legs"]]

    route = route_m / KM
    track = track_m / KM
    view = MapView.of(np.r_[route[:, 0], track[:, 0]], np.r_[route[:, 1], track[:, 1]], 0.045)
    fig, axy, axz, axv, axh = _budget_layout(view.aspect)

    ring = np.array(unreliable)
    _draw_plan_view(axy, route, track, kinds, ring)
    view.apply(axy, "plan view")

    helices = draw_side_view(axz, track_m, along, route_m, ids, kinds, entry)
    margins = []
    for ax, component, resets in ((axv, "v", "V"), (axh, "h", "H")):
        margins.append(_budget(ax, entry, along, kinds, component, resets, unreliable, residual))
    axh.set_xlabel("distance flown (km)")
    plt.setp(axz.get_xticklabels(), visible=False)
    plt.setp(axv.get_xticklabels(), visible=False)

    fig.legend(
        handles=_legend(residual), loc="outside lower center", ncol=4, fontsize=10, frameon=False
    )
    fig.suptitle("error budget — " + route_title(plan, k, entry), fontsize=14)
    placer = LabelPlacer(fig)
    label_route(placer, axy, route[:, :2], ids, [track[:, :2]], BUDGET_SIZES, ring)
    label_side_view(placer, axz, track_m, along, route_m, ids, helices)
    for ax, (labels, markers, lines) in zip((axv, axh), margins, strict=True):
        left_out(ax, placer.place(ax, labels, markers, lines), "margin")
    return fig


def _draw_plan_view(
    axy: Axes, route: np.ndarray, track: np.ndarray, kinds: np.ndarray, ring: np.ndarray
) -> None:
    """The route's points (km) on the plan view over its flown track, the ``ring``ed ones
    (unreliable) ringed."""
    axy.plot(track[:, 0], track[:, 1], color=COLOURS["track"], lw=1.4)
    for letter in ("V", "H"):
        sel = kinds == letter
        axy.scatter(
            route[sel, 0],
            route[sel, 1],
            s=BUDGET_SIZES[0],
            c=COLOURS[letter],
            marker="o" if letter == "V" else "^",
            edgecolors="black",
            zorder=3,
        )
    if ring.any():
        axy.scatter(route[ring, 0], route[ring, 1], s=RING_SIZE, fc="none", ec=UNRELIABLE, lw=1.5)
    axy.scatter(*route[0, :2], s=BUDGET_SIZES[1], c=COLOURS["A"], marker="*", ec="k", zorder=4)
    axy.scatter(*route[-1, :2], s=BUDGET_SIZES[2], c=COLOURS["B"], marker="s", ec="k", zorder=4)


def _legend(residual: float) -> list[Line2D]:
    """The error budget's legend (``residual``: the error a failed correction leaves)."""
    return [
        Line2D([], [], color=COLOURS["V"], lw=1.6, label="error (corrections succeed)"),
        Line2D(
            [],
            [],
            ls="",
            marker="_",
            ms=16,
            mew=2.5,
            color=LIMIT,
            label="the point's limit on arrival",
        ),
        Line2D([], [], color=MARGIN, lw=3, alpha=0.5, label="margin left on arrival"),
        Line2D(
            [],
            [],
            ls="",
            marker="o",
            ms=7,
            mfc="none",
            mec=UNRELIABLE,
            label=f"error left if an unreliable correction fails (min(error, {residual:g}))",
        ),
    ]


def error_budget_png(plan: dict, route_index: int | None = None) -> bytes:
    """``error_budget_figure`` as PNG bytes."""
    return to_png(error_budget_figure(plan, route_index))


def _budget(ax, entry: dict, along, kinds, component: str, resets: str, unreliable, residual):
    """One component's sawtooth: growth along each leg, the drop at each correcting point, the
    limit (a bar) and the margin (a band from the error up to the limit) at every point.
    Returns the margins' labels, the markers and the lines they keep clear of."""
    legs = entry["legs"]
    arrival = np.array([0.0] + [float(leg[f"{component}_error"]) for leg in legs])
    limit = np.array([np.nan] + [float(leg[f"{component}_limit"]) for leg in legs])
    x = along / KM
    sx, sy = sawtooth(entry, component, resets)
    colour = COLOURS["V"] if component == "v" else COLOURS["H"]
    ax.plot(sx / KM, sy, color=colour, lw=1.6)
    ax.scatter(x[1:], arrival[1:], s=22, color=colour, zorder=3)
    ax.scatter(x[1:], limit[1:], marker="_", s=260, linewidths=2.5, color=LIMIT, zorder=4)
    ax.vlines(x[1:], arrival[1:], limit[1:], color=MARGIN, lw=3, alpha=0.5, zorder=2)
    tight = np.nanargmin(limit[1:] - arrival[1:]) + 1
    labels = []
    for n in range(1, len(x)):
        margin = limit[n] - arrival[n]
        labels.append(
            Label(
                f"{margin:.2f}" if margin < 1 else f"{margin:.1f}",
                (x[n], limit[n]),
                priority=0 if n == tight else 1,
                size=8,
                weight="bold" if n == tight else "normal",
                colour=LIMIT if n == tight else "0.25",
                clearance=2.0,
                directions=ABOVE,
            )
        )
    fails = [n for n in range(1, len(x)) if unreliable[n] and kinds[n] == resets]
    if fails:
        ax.scatter(
            x[fails],
            np.minimum(arrival[fails], residual),
            s=45,
            fc="none",
            ec=UNRELIABLE,
            lw=1.4,
            zorder=4,
        )
    # The corrections of this component, with the ids of the points that make them.
    for n in np.flatnonzero(kinds == resets):
        ax.axvline(x[n], color=colour, lw=0.6, alpha=0.25)
    name = "vertical" if component == "v" else "horizontal"
    ax.set_ylabel(f"{name} error (units)")
    top = np.nanmax(np.concatenate([limit[1:], arrival]))
    ax.set_ylim(0, top * 1.22)
    ax.set_title(
        f"{name} error: reset at {resets} points; limits and margins on arrival "
        f"(tightest {limit[tight] - arrival[tight]:.2f} at {entry['route'][tight]})",
        fontsize=11,
    )
    ax.grid(True, alpha=0.3)
    bars = np.column_stack([x[1:], limit[1:]])
    dots = np.column_stack([x[1:], arrival[1:]])
    markers = [(bars, (8.0, 2.0)), (dots, marker_radius(22))]
    lines = [np.column_stack([sx / KM, sy])]
    lines += [np.array([[x[n], arrival[n]], [x[n], limit[n]]]) for n in range(1, len(x))]
    return labels, markers, lines
