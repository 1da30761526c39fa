"""Pictures of a contingency policy, PNG, headless (see mission/pictures.py).

* ``tree_png``: the policy on the map (plan view): the primary mission's flown track, each branch
  mission's track from where it leaves its parent, the points whose failed fix switches missions
  marked and labelled with the mission switched to.
* ``policy_front_png``: F3 (probability of arriving) against F1 (longest length) for each route
  of the front and for the policy replanned from it, an arrow from each route to its policy.

Labels are placed as in mission/pictures.py (``LabelPlacer``): none overprints another. The
``*_figure`` functions return the drawn figure, for tests to measure.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.map_view import MapView
from gcs_planner.mission.picture_axes import (
    COLOURS,
    DPI,
    KM,
    UNRELIABLE,
    plan_points,
    plt,
    to_png,
)
from gcs_planner.mission.picture_labels import Label, LabelPlacer, marker_radius
from gcs_planner.mission.policy_build import MissionPath, PathSwitch

BRANCH_COLOURS = ("#9467bd", "#17becf", "#e377c2", "#8c564b", "#bcbd22", "#7f7f7f", "#ff7f0e")


# The labels keep clear of the tracks as polylines of at most this many samples: a dataset's
# track has tens of thousands (metres apart), and the placer tests every label's candidate spots
# against every segment. Straight legs lose nothing; a turn becomes chords a few pixels long
# at a map of a few hundred kilometres.
PLACER_SAMPLES = 400


def _thinned(track: np.ndarray) -> np.ndarray:
    """``track`` with every k-th sample (and its last) so that at most PLACER_SAMPLES remain."""
    step = -(-len(track) // PLACER_SAMPLES)
    if step <= 1:
        return track
    return np.vstack([track[::step], track[-1:]])


def _leave_index(track: np.ndarray, parent: np.ndarray) -> int:
    """Index in ``track`` of the last sample it shares with ``parent`` (the branch's items
    equal the parent's up to the failed point, so their tracks agree sample for sample)."""
    n = min(len(track), len(parent))
    if n < 2:
        return 0
    # Every sample compared at once (a branch's track has thousands): np.allclose's rule.
    same = np.isclose(track[1:n], parent[1:n], atol=1e-6).all(axis=1)
    differs = np.flatnonzero(~same)
    return int(differs[0]) if len(differs) else n - 1


def tree_figure(
    plan: dict,
    missions: list[tuple[MissionPath, dict]],
    switches: list[PathSwitch],
    title: str,
) -> Figure:
    """The policy's missions on the map. ``plan``: the scenario's plan dict (its points);
    ``missions``: each mission's path and one-route plan, primary first. The map is cropped to
    the points and tracks; labels are placed so that none overprints another (A and B first,
    then the failed fixes and the missions they switch to, then the missions' points)."""
    xyz, kind, unreliable = plan_points(plan)
    xyz = xyz / KM
    ids = [str(p.get("id")) for p in plan.get("points") or []]
    tracks = {p.name: trajectory_local(d, 0) / KM for p, d in missions}
    every = np.vstack([xyz[:, :2], *(t[:, :2] for t in tracks.values())])
    view = MapView.of(every[:, 0], every[:, 1])

    # A square-ish map with the legend on its right, a flat one with the legend below.
    beside = view.aspect >= 0.6
    if beside:
        map_h = 6.6
        map_w = float(np.clip(map_h / view.aspect, 3.5, 8.0)) + 1.0
        figsize = (map_w + 5.5, map_h + 1.0)
    else:
        map_h = float(np.clip(11.0 * view.aspect, 1.8, 6.0)) + 0.8
        figsize = (12.0, map_h + 0.9 + 0.2 * (len(missions) + 4))
    fig, ax = plt.subplots(figsize=figsize, layout="constrained", dpi=DPI)
    for letter, marker in (("V", "o"), ("H", "^")):
        sel = kind == letter
        if sel.any():
            ax.scatter(
                xyz[sel, 0],
                xyz[sel, 1],
                s=10,
                c=COLOURS[letter],
                alpha=0.35,
                marker=marker,
                label=f"{letter} point",
            )
    if unreliable.any():
        ax.scatter(
            xyz[unreliable, 0],
            xyz[unreliable, 1],
            s=60,
            facecolors="none",
            edgecolors=UNRELIABLE,
            lw=0.8,
            alpha=0.6,
            label="unreliable point",
        )
    _draw_missions(ax, missions, tracks, xyz, ids)
    by_point: dict[int, list[str]] = {}
    for s in switches:  # one label per point, a line per context it fails in
        by_point.setdefault(s.failed, []).append(f"{s.mission} \u2192 {s.to}")
    for j in by_point:
        ax.scatter(
            [xyz[j, 0]], [xyz[j, 1]], s=FAIL_SIZE, marker="X", c=UNRELIABLE, ec="k", zorder=5
        )
    start = missions[0][0].points
    ends = (
        (start[0], "*", COLOURS["A"], END_SIZES[0]),
        (start[-1], "s", COLOURS["B"], END_SIZES[1]),
    )
    for j, marker, colour, size in ends:
        ax.scatter([xyz[j, 0]], [xyz[j, 1]], s=size, marker=marker, c=colour, ec="k", zorder=6)
    ax.scatter([], [], s=120, marker="X", c=UNRELIABLE, ec="k", label="failed fix: switch mission")
    view.apply(ax, title)
    ax.title.set_fontsize(12)
    if beside:
        fig.legend(loc="outside right upper", ncol=1, fontsize=9, frameon=False)
    else:
        fig.legend(loc="outside lower center", ncol=1, fontsize=9, frameon=False)

    labels, markers = _tree_labels(missions, xyz, ids, ends, by_point)
    placer = LabelPlacer(fig)
    dropped = placer.place(ax, labels, markers, [_thinned(t[:, :2]) for t in tracks.values()])
    if dropped:
        plural = "" if dropped == 1 else "s"
        ax.set_title(f"{ax.get_title()}\n({dropped} label{plural} left out: no room)", fontsize=12)
    return fig


def _draw_missions(
    ax: Axes,
    missions: list[tuple[MissionPath, dict]],
    tracks: dict[str, np.ndarray],
    xyz: np.ndarray,
    ids: list[str],
) -> None:
    """Each mission's track (km) and the points it adds: the primary's whole, each branch's
    from where it leaves its parent, dashed in its own colour."""
    for n, (path, _) in enumerate(missions):
        track = tracks[path.name]
        if path.parent is None:
            ax.plot(
                track[:, 0],
                track[:, 1],
                color=COLOURS["track"],
                lw=2.0,
                label=f"{path.name} (every fix takes)",
                zorder=3,
            )
            on = list(path.points)  # the plan's points are in scenario index order
            ax.scatter(xyz[on, 0], xyz[on, 1], s=POINT_SIZE, c="k", zorder=4)
            continue
        colour = BRANCH_COLOURS[(n - 1) % len(BRANCH_COLOURS)]
        k = _leave_index(track, tracks[path.parent])
        label = f"{path.name}: after the fix at {ids[path.failed]} fails (from {path.parent})"
        if k + 1 >= len(track):
            # The same points as its parent: only the switches further on differ.
            label += ", same track, other switches later"
        ax.plot(track[k:, 0], track[k:, 1], color=colour, lw=1.8, ls="--", zorder=3, label=label)
        parent = next(p.points for p, _ in missions if p.name == path.parent)
        on = [j for j in path.points if j not in parent]
        if on:
            ax.scatter(xyz[on, 0], xyz[on, 1], s=POINT_SIZE, c=colour, ec="k", zorder=4)


def _tree_labels(
    missions: list[tuple[MissionPath, dict]],
    xyz: np.ndarray,
    ids: list[str],
    ends: tuple[tuple[int, str, str, float], ...],
    by_point: dict[int, list[str]],
) -> tuple[list[Label], list[tuple[np.ndarray, float]]]:
    """The labels (A and B, the failed fixes with the switches they make, the missions'
    points) and the markers they keep clear of."""
    start = missions[0][0].points
    labels = [
        Label(ids[j], tuple(xyz[j, :2]), 0, 12, "bold", "black", marker_radius(size))
        for j, _, _, size in ends
    ]
    fail_r = marker_radius(FAIL_SIZE)
    labels += [
        Label(
            f"{ids[j]} fails: " + "\n".join(lines),
            tuple(xyz[j, :2]),
            1,
            9,
            colour=UNRELIABLE,
            clearance=fail_r,
            gaps=FAR_GAPS,
        )
        for j, lines in by_point.items()
    ]
    named = {start[0], start[-1], *by_point}
    points = sorted({j for p, _ in missions for j in p.points[1:-1]} - named)
    labels += [
        Label(ids[j], tuple(xyz[j, :2]), 2 + n % 2, clearance=marker_radius(POINT_SIZE))
        for n, j in enumerate(points)
    ]
    marked = sorted({j for p, _ in missions for j in p.points})
    markers = [(xyz[marked, :2], marker_radius(POINT_SIZE))]
    markers += [(xyz[list(by_point), :2], fail_r)] if by_point else []
    markers += [(xyz[[j], :2], marker_radius(size)) for j, _, _, size in ends]
    return labels, markers


def tree_png(
    plan: dict,
    missions: list[tuple[MissionPath, dict]],
    switches: list[PathSwitch],
    title: str,
) -> bytes:
    """``tree_figure`` as PNG bytes."""
    return to_png(tree_figure(plan, missions, switches, title))


# Marker areas (points²): the missions' points, the failed fixes, A and B.
POINT_SIZE, FAIL_SIZE, END_SIZES = 40.0, 220.0, (300.0, 150.0)
# The failed fixes' labels may go further out, tied to their point by a leader line.
FAR_GAPS = (3.0, 10.0, 20.0, 34.0, 52.0, 75.0, 100.0)


def policy_front_figure(
    rows: list[tuple[int, float, float, float, float]], chosen: int, title: str
) -> Figure:
    """``rows``: (front index, route F1 m, route F3, policy F1 m, policy F3) per front route;
    each route named beside its point, no name over another."""
    fig, ax = plt.subplots(figsize=(9, 6.5), layout="constrained", dpi=DPI)
    r = np.array([[L, p, PL, pp] for _, L, p, PL, pp in rows], dtype=float).reshape(-1, 4)
    r[:, [0, 2]] /= KM
    arrows = []
    for L, p, PL, pp in r:
        if abs(PL - L) > 1e-9 or abs(pp - p) > 1e-12:
            ax.annotate(
                "", (PL, pp), (L, p), arrowprops={"arrowstyle": "->", "color": "0.5", "lw": 1}
            )
            arrows.append(np.array([[L, p], [PL, pp]]))
    ax.scatter(
        r[:, 0],
        r[:, 1],
        s=60,
        c=COLOURS["V"],
        ec="k",
        lw=0.6,
        zorder=3,
        label="route of the front (F1 = its length)",
    )
    ax.scatter(
        r[:, 2],
        r[:, 3],
        s=80,
        marker="^",
        c=COLOURS["H"],
        ec="k",
        lw=0.6,
        zorder=3,
        label="policy replanned from it (F1 = its longest outcome)",
    )
    c = [i for i, row in enumerate(rows) if row[0] == chosen]
    if c:
        i = c[0]
        ax.scatter(
            r[i, [0, 2]],
            r[i, [1, 3]],
            s=320,
            facecolors="none",
            ec=COLOURS["B"],
            lw=2.0,
            zorder=4,
            label=f"chosen route {chosen} and its policy",
        )
    ax.margins(x=0.1, y=0.1)
    ax.set_xlabel("F1: longest flown length (km)")
    ax.set_ylabel("F3: probability of arriving")
    ax.grid(True, alpha=0.3)
    fig.legend(loc="outside lower center", ncol=1, fontsize=10, frameon=False)
    ax.set_title(title, fontsize=12)
    placer = LabelPlacer(fig)
    labels = [
        Label(f"route {k}", (L, p), size=8, colour="0.3", clearance=marker_radius(60))
        for (k, *_), (L, p, _, _) in zip(rows, r, strict=True)
    ]
    markers = [(r[:, :2], marker_radius(60)), (r[:, 2:], marker_radius(80))]
    if c:
        markers.append((np.vstack([r[c[0], :2], r[c[0], 2:]]), marker_radius(320)))
    dropped = placer.place(ax, labels, markers, arrows)
    if dropped:
        plural = "" if dropped == 1 else "s"
        ax.set_title(f"{title} ({dropped} name{plural} left out: no room)", fontsize=12)
    return fig


def policy_front_png(
    rows: list[tuple[int, float, float, float, float]], chosen: int, title: str
) -> bytes:
    """``policy_front_figure`` as PNG bytes."""
    return to_png(policy_front_figure(rows, chosen, title))
