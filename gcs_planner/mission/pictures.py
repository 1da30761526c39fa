"""Pictures of a plan, PNG, headless (matplotlib's Agg backend).

* ``route_png``: the route in 3D over all correction points (V and H in two colours, unreliable
  points ringed, A and B marked, the flown trajectory with its turns), beside its XOY (plan view)
  and XOZ (side view) projections, as in the paper's Figure 8.
* ``front_png``: the Pareto front, length against corrections, the chosen route highlighted and
  the success probability as colour when the plan has it.

Both return PNG bytes; writing them (atomically) is the caller's business.
"""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from gcs_planner.mission.builder import route_entry, route_legs, route_xyz  # noqa: E402
from gcs_planner.mission.geo_exports import trajectory_local  # noqa: E402

COLOURS = {"V": "#1f77b4", "H": "#ff7f0e", "A": "#2ca02c", "B": "#d62728", "track": "#222222"}
UNRELIABLE = "#d62728"
KM = 1000.0
DPI = 110


def _png(fig: Figure) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    plt.close(fig)
    return buf.getvalue()


def _points(plan: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(n, 3) positions, kinds and unreliable flags of every point of the plan."""
    pts = plan.get("points") or []
    xyz = np.array([[p["x"], p["y"], p["z"]] for p in pts], dtype=float).reshape(-1, 3)
    kind = np.array([str(p.get("kind", "")) for p in pts])
    unreliable = np.array([bool(p.get("unreliable", False)) for p in pts], dtype=bool)
    return xyz, kind, unreliable


def _scatter(ax, pts: np.ndarray, dims: tuple[int, ...], **kw) -> None:
    """Scatter rows of ``pts`` (or one point) on the axes ``dims``; no depth shading in 3D,
    which would make far points look like a different colour."""
    pts = np.atleast_2d(pts)
    if len(dims) == 3:
        kw["depthshade"] = False
    ax.scatter(*(pts[:, d] for d in dims), **kw)


def _title(plan: dict, k: int, entry: dict) -> str:
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


def route_png(plan: dict, route_index: int | None = None) -> bytes:
    """The route over all correction points: 3D view, XOY and XOZ projections."""
    k, entry = route_entry(plan, route_index)
    legs = route_legs(entry)
    route = route_xyz(plan, entry, legs) / KM
    track = trajectory_local(plan, k) / KM
    xyz, kind, unreliable = _points(plan)
    xyz = xyz / KM
    on_route = {str(pid) for pid in entry["route"]}
    ids = [str(p.get("id")) for p in plan.get("points") or []]
    visited = np.array([pid in on_route for pid in ids], dtype=bool)

    fig = plt.figure(figsize=(15, 8.5), layout="constrained")
    grid = fig.add_gridspec(2, 2, width_ratios=[1.25, 1])
    ax3 = fig.add_subplot(grid[:, 0], projection="3d")
    axy = fig.add_subplot(grid[0, 1])
    axz = fig.add_subplot(grid[1, 1])
    views = [(ax3, (0, 1, 2)), (axy, (0, 1)), (axz, (0, 2))]

    layers = [  # (selection, scatter style), drawn in this order
        ((kind == "V") & ~visited, {"s": 9, "c": COLOURS["V"], "alpha": 0.35, "marker": "o"}),
        ((kind == "H") & ~visited, {"s": 9, "c": COLOURS["H"], "alpha": 0.35, "marker": "^"}),
        (unreliable & ~visited, {"s": 14, "c": UNRELIABLE, "marker": "x", "lw": 0.6, "alpha": 0.6}),
        ((kind == "V") & visited, {"s": 70, "c": COLOURS["V"], "marker": "o", "ec": "k"}),
        ((kind == "H") & visited, {"s": 70, "c": COLOURS["H"], "marker": "^", "ec": "k"}),
        (unreliable & visited, {"s": 220, "fc": "none", "ec": UNRELIABLE, "lw": 1.6}),
    ]
    for ax, dims in views:
        for sel, style in layers:
            if sel.any():
                _scatter(ax, xyz[sel], dims, **style)
        ax.plot(*(track[:, d] for d in dims), color=COLOURS["track"], lw=1.6)
        _scatter(ax, route[0], dims, s=300, c=COLOURS["A"], marker="*", ec="k", zorder=5)
        _scatter(ax, route[-1], dims, s=150, c=COLOURS["B"], marker="s", ec="k", zorder=5)
        for label, end in (("A", route[0]), ("B", route[-1])):
            ax.text(*(end[d] for d in dims), f"  {label}", fontsize=13, fontweight="bold")

    ax3.set_xlabel("x east (km)")
    ax3.set_ylabel("y north (km)")
    ax3.set_zlabel("z up (km)")
    ax3.set_title("3D view")
    ax3.view_init(elev=24, azim=-60)
    axy.set_xlabel("x east (km)")
    axy.set_ylabel("y north (km)")
    axy.set_title("XOY projection (plan view)")
    axz.set_xlabel("x east (km)")
    axz.set_ylabel("z up (km)")
    axz.set_title("XOZ projection (side view)")
    for ax in (axy, axz):
        ax.grid(True, alpha=0.3)

    handles = [
        Line2D([], [], color=COLOURS["track"], lw=1.6, label="flown trajectory (arcs + straights)"),
        Line2D(
            [],
            [],
            ls="",
            marker="o",
            ms=8,
            mfc=COLOURS["V"],
            mec="black",
            label="V point (vertical correction) on route",
        ),
        Line2D(
            [],
            [],
            ls="",
            marker="^",
            ms=8,
            mfc=COLOURS["H"],
            mec="black",
            label="H point (horizontal correction) on route",
        ),
        Line2D(
            [],
            [],
            ls="",
            marker="o",
            ms=4,
            mfc=COLOURS["V"],
            mec="none",
            alpha=0.5,
            label="other V points",
        ),
        Line2D(
            [],
            [],
            ls="",
            marker="^",
            ms=4,
            mfc=COLOURS["H"],
            mec="none",
            alpha=0.5,
            label="other H points",
        ),
        Line2D(
            [],
            [],
            ls="",
            marker="o",
            ms=13,
            mfc="none",
            mec=UNRELIABLE,
            mew=1.6,
            label="unreliable correction point (x when off route)",
        ),
        Line2D([], [], ls="", marker="*", ms=15, mfc=COLOURS["A"], mec="black", label="A (start)"),
        Line2D([], [], ls="", marker="s", ms=10, mfc=COLOURS["B"], mec="black", label="B (end)"),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=10, frameon=False)
    fig.suptitle(_title(plan, k, entry), fontsize=14)
    return _png(fig)


def front_png(plan: dict) -> bytes:
    """The Pareto front: flown length against the number of corrections."""
    front = plan["front"]
    route_entry(plan)  # validates the plan and its chosen index
    chosen = int(plan.get("chosen", 0))
    corr = np.array([r.get("corrections", len(r["route"]) - 2) for r in front], dtype=float)
    length = np.array([r["length"] for r in front], dtype=float) / KM
    prob = np.array([r.get("probability", 1.0) for r in front], dtype=float)
    with_p = "probability" in (plan.get("objectives") or [])

    fig, ax = plt.subplots(figsize=(9, 6.5), layout="constrained")
    order = np.lexsort((length, corr))
    if not with_p:  # with two objectives the front is a staircase worth drawing as a line
        ax.plot(corr[order], length[order], color="0.6", lw=1, zorder=1)
    if with_p:
        sc = ax.scatter(
            corr,
            length,
            c=prob,
            cmap="viridis",
            vmin=min(prob.min(), 0.999 * prob.max()),
            vmax=prob.max(),
            s=70,
            edgecolors="black",
            linewidths=0.6,
            zorder=2,
        )
        fig.colorbar(sc, ax=ax, label="success probability")
        if len(front) <= 20:
            for c, L, pr in zip(corr, length, prob, strict=True):
                ax.annotate(
                    f"P {pr:.3f}",
                    (c, L),
                    xytext=(8, -4),
                    textcoords="offset points",
                    fontsize=9,
                    color="0.3",
                )
    else:
        ax.scatter(corr, length, s=70, c=COLOURS["V"], edgecolors="black", lw=0.6, zorder=2)
    ax.scatter(
        corr[chosen],
        length[chosen],
        s=320,
        facecolors="none",
        edgecolors=COLOURS["B"],
        linewidths=2.2,
        zorder=3,
        label=f"chosen route ({plan.get('choice', 'chosen')})",
    )
    text = f"  route {chosen}: {corr[chosen]:.0f} corrections, {length[chosen]:.2f} km"
    if with_p:
        text += f", P {prob[chosen]:.3f}"
    # Text towards the middle of the plot, so it never pushes the axes out of the figure.
    right = corr[chosen] > (corr.min() + corr.max()) / 2
    ax.annotate(
        text.strip(),
        (corr[chosen], length[chosen]),
        xytext=(-16 if right else 16, -22 if length[chosen] > length.mean() else 16),
        textcoords="offset points",
        ha="right" if right else "left",
        fontsize=11,
        color=COLOURS["B"],
    )
    ax.margins(x=0.08, y=0.1)
    ax.set_xlabel("number of corrections")
    ax.set_ylabel("flown length (km)")
    ax.xaxis.get_major_locator().set_params(integer=True)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best")
    scen = (plan.get("scenario") or {}).get("name", "scenario")
    ax.set_title(
        f"{scen}: Pareto front ({len(front)} routes; objectives: "
        f"{', '.join(plan.get('objectives') or ['length', 'corrections'])})"
    )
    return _png(fig)
