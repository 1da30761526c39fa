"""Pictures of a contingency policy, PNG, headless (see mission/pictures.py).

* ``tree_png``: the policy on the map (plan view): the primary mission's flown track, each branch
  mission's track from where it leaves its parent, the points whose failed fix switches missions
  marked and labelled with the mission switched to.
* ``policy_front_png``: F3 (probability of arriving) against F1 (longest length) for each route
  of the front and for the policy replanned from it, an arrow from each route to its policy.
"""

from __future__ import annotations

import numpy as np

from gcs_planner.mission.geo_exports import trajectory_local
from gcs_planner.mission.pictures import COLOURS, KM, UNRELIABLE, _png, _points, plt
from gcs_planner.mission.policy_build import MissionPath, PathSwitch

BRANCH_COLOURS = ("#9467bd", "#17becf", "#e377c2", "#8c564b", "#bcbd22", "#7f7f7f", "#ff7f0e")


def _leave_index(track: np.ndarray, parent: np.ndarray) -> int:
    """Index in ``track`` of the last sample it shares with ``parent`` (the branch's items
    equal the parent's up to the failed point, so their tracks agree sample for sample)."""
    k = 0
    n = min(len(track), len(parent))
    while k + 1 < n and np.allclose(track[k + 1], parent[k + 1], atol=1e-6):
        k += 1
    return k


def tree_png(
    plan: dict,
    missions: list[tuple[MissionPath, dict]],
    switches: list[PathSwitch],
    title: str,
) -> bytes:
    """The policy's missions on the map. ``plan``: the scenario's plan dict (its points);
    ``missions``: each mission's path and one-route plan, primary first."""
    xyz, kind, unreliable = _points(plan)
    xyz = xyz / KM
    ids = [str(p.get("id")) for p in plan.get("points") or []]
    tracks = {p.name: trajectory_local(d, 0) / KM for p, d in missions}

    fig, ax = plt.subplots(figsize=(11, 8.5), layout="constrained")
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
            ax.scatter(xyz[on, 0], xyz[on, 1], s=40, c="k", zorder=4)
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
            ax.scatter(xyz[on, 0], xyz[on, 1], s=40, c=colour, ec="k", zorder=4)
    labelled = sorted({j for p, _ in missions for j in p.points[1:-1]})
    for j in labelled:
        ax.annotate(
            ids[j],
            (xyz[j, 0], xyz[j, 1]),
            xytext=(-4, 7),
            textcoords="offset points",
            fontsize=8.5,
            color="0.2",
            ha="right",
        )
    by_point: dict[int, list[str]] = {}
    for s in switches:  # one label per point, a line per context it fails in
        by_point.setdefault(s.failed, []).append(f"{s.mission} \u2192 {s.to}")
    for j, lines in by_point.items():
        x, y = xyz[j, 0], xyz[j, 1]
        ax.scatter([x], [y], s=220, marker="X", c=UNRELIABLE, ec="k", zorder=5)
        ax.annotate(
            f"{ids[j]} fails: " + "\n".join(lines),
            (x, y),
            xytext=(8, -14),
            textcoords="offset points",
            fontsize=9,
            color=UNRELIABLE,
            va="top",
        )
    start = missions[0][0].points
    for j, marker, colour, size in (
        (start[0], "*", COLOURS["A"], 300),
        (start[-1], "s", COLOURS["B"], 150),
    ):
        ax.scatter([xyz[j, 0]], [xyz[j, 1]], s=size, marker=marker, c=colour, ec="k", zorder=6)
        ax.annotate(
            ids[j],
            (xyz[j, 0], xyz[j, 1]),
            xytext=(6, 6),
            textcoords="offset points",
            fontsize=12,
            fontweight="bold",
        )
    ax.scatter([], [], s=120, marker="X", c=UNRELIABLE, ec="k", label="failed fix: switch mission")
    ax.set_xlabel("x east (km)")
    ax.set_ylabel("y north (km)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    fig.legend(loc="outside lower center", ncol=1, fontsize=9, frameon=False)
    ax.set_title(title, fontsize=12)
    return _png(fig)


def policy_front_png(
    rows: list[tuple[int, float, float, float, float]], chosen: int, title: str
) -> bytes:
    """``rows``: (front index, route F1 m, route F3, policy F1 m, policy F3) per front route."""
    fig, ax = plt.subplots(figsize=(9, 6.5), layout="constrained")
    r = np.array([[L, p, PL, pp] for _, L, p, PL, pp in rows], dtype=float).reshape(-1, 4)
    r[:, [0, 2]] /= KM
    for (k, *_), (L, p, PL, pp) in zip(rows, r, strict=True):
        if abs(PL - L) > 1e-9 or abs(pp - p) > 1e-12:
            ax.annotate(
                "", (PL, pp), (L, p), arrowprops={"arrowstyle": "->", "color": "0.5", "lw": 1}
            )
        ax.annotate(
            f"route {k}",
            (L, p),
            xytext=(-12, 8),
            textcoords="offset points",
            fontsize=8,
            color="0.3",
            ha="right",
        )
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
    return _png(fig)
