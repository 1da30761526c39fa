"""Pictures of a plan, PNG, headless (matplotlib's Agg backend).

* ``route_png``: the route in 3D over all correction points (V and H in two colours, unreliable
  points ringed, A and B marked, the flown trajectory with its turns), beside its XOY (plan view)
  and XOZ (side view) projections, as in the paper's Figure 8.
* ``front_png``: the Pareto front, length against corrections, the chosen route highlighted and
  the success probability as colour when the plan has it; it reads with one route and with fifty.
* ``error_budget_png``: what an operator checks before flying: the vertical and horizontal error
  against distance flown (the sawtooth of corrections), each point's limits and the margin left
  at it, beside the plan view and the side view (altitude against distance flown).

Route points carry their ids, as the scenario file names them.

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

LIMIT = "#d62728"
MARGIN = "#2ca02c"
# Above this many route points their id labels would overlap: label every other one.
MAX_LABELS = 30

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


def _flown_distance(track: np.ndarray) -> np.ndarray:
    """Distance flown (same unit as ``track``) at each vertex of the flown polyline."""
    steps = np.linalg.norm(np.diff(track, axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def _route_stops(entry: dict) -> tuple[list[str], np.ndarray]:
    """Ids of the route's points and the distance flown (m) at each, A first."""
    ids = [str(pid) for pid in entry["route"]]
    along = [0.0] + [float(leg.get("cumulative", np.nan)) for leg in entry["legs"]]
    return ids, np.asarray(along, dtype=float)


def _label_points(ax, xs, ys, ids: list[str], **kw) -> None:
    """Each route point's id beside it (every other one on a long route), A and B in bold."""
    step = 1 if len(ids) <= MAX_LABELS else 2
    for n, (x, y, pid) in enumerate(zip(xs, ys, ids, strict=True)):
        end = n in (0, len(ids) - 1)
        if not end and n % step:
            continue
        ax.annotate(
            pid,
            (x, y),
            xytext=(4, 5),
            textcoords="offset points",
            fontsize=12 if end else 8.5,
            fontweight="bold" if end else "normal",
            color="black" if end else "0.2",
            **kw,
        )


def side_profile(plan: dict, route_index: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(distance flown in metres, altitude z in metres) along the route's flown polyline: the
    side view an operator reads climbs, descents and helices from."""
    track = trajectory_local(plan, route_index)
    return _flown_distance(track), track[:, 2]


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


def _side_view(
    ax, track: np.ndarray, stops_along: np.ndarray, route: np.ndarray, ids, kinds, entry: dict
):
    """Altitude against distance flown, from the flown polyline: climbs, descents and helices
    appear as flown (a helix keeps the leg's constant path angle, so it is named beside it)."""
    along = _flown_distance(track)
    ax.plot(along / KM, track[:, 2], color=COLOURS["track"], lw=1.4)
    for n, leg in enumerate(entry["legs"]):
        turns = int(leg.get("helix_turns", 0) or 0)
        if turns:
            ax.annotate(
                f"helix: {turns} turn{'s' if turns > 1 else ''}",
                (
                    (stops_along[n] + stops_along[n + 1]) / 2 / KM,
                    (route[n, 2] + route[n + 1, 2]) / 2,
                ),
                xytext=(6, 0),
                textcoords="offset points",
                fontsize=9,
                color="#9467bd",
                fontweight="bold",
            )
    for k in ("V", "H"):
        sel = kinds == k
        ax.scatter(
            stops_along[sel] / KM,
            route[sel, 2],
            s=40,
            c=COLOURS[k],
            marker="o" if k == "V" else "^",
            edgecolors="black",
            zorder=3,
        )
    ax.scatter(
        stops_along[0] / KM, route[0, 2], s=200, c=COLOURS["A"], marker="*", ec="k", zorder=4
    )
    ax.scatter(
        stops_along[-1] / KM, route[-1, 2], s=90, c=COLOURS["B"], marker="s", ec="k", zorder=4
    )
    _label_points(ax, stops_along / KM, route[:, 2], ids)
    ax.set_ylabel("altitude z (m)")
    ax.set_title("side view: altitude against distance flown")
    ax.margins(y=0.12)
    ax.grid(True, alpha=0.3)


def route_png(plan: dict, route_index: int | None = None) -> bytes:
    """The route over all correction points: 3D view, plan view and side view (altitude against
    distance flown), the route's points labelled with their ids."""
    k, entry = route_entry(plan, route_index)
    legs = route_legs(entry)
    route_m = route_xyz(plan, entry, legs)
    route = route_m / KM
    track_m = trajectory_local(plan, k)
    track = track_m / KM
    xyz, kind, unreliable = _points(plan)
    xyz = xyz / KM
    route_ids, along = _route_stops(entry)
    on_route = set(route_ids)
    ids = [str(p.get("id")) for p in plan.get("points") or []]
    visited = np.array([pid in on_route for pid in ids], dtype=bool)
    route_kinds = _route_kinds(plan, entry)

    fig = plt.figure(figsize=(15, 8.5), layout="constrained")
    grid = fig.add_gridspec(2, 2, width_ratios=[1.25, 1])
    ax3 = fig.add_subplot(grid[:, 0], projection="3d")
    axy = fig.add_subplot(grid[0, 1])
    axz = fig.add_subplot(grid[1, 1])

    layers = [  # (selection, scatter style), drawn in this order
        ((kind == "V") & ~visited, {"s": 9, "c": COLOURS["V"], "alpha": 0.35, "marker": "o"}),
        ((kind == "H") & ~visited, {"s": 9, "c": COLOURS["H"], "alpha": 0.35, "marker": "^"}),
        (unreliable & ~visited, {"s": 14, "c": UNRELIABLE, "marker": "x", "lw": 0.6, "alpha": 0.6}),
        ((kind == "V") & visited, {"s": 70, "c": COLOURS["V"], "marker": "o", "ec": "k"}),
        ((kind == "H") & visited, {"s": 70, "c": COLOURS["H"], "marker": "^", "ec": "k"}),
        (unreliable & visited, {"s": 220, "fc": "none", "ec": UNRELIABLE, "lw": 1.6}),
    ]
    for ax, dims in ((ax3, (0, 1, 2)), (axy, (0, 1))):
        for sel, style in layers:
            if sel.any():
                _scatter(ax, xyz[sel], dims, **style)
        ax.plot(*(track[:, d] for d in dims), color=COLOURS["track"], lw=1.6)
        _scatter(ax, route[0], dims, s=300, c=COLOURS["A"], marker="*", ec="k", zorder=5)
        _scatter(ax, route[-1], dims, s=150, c=COLOURS["B"], marker="s", ec="k", zorder=5)
    for n, pid in enumerate(route_ids):  # 3D text has no offset points: a small shift in km
        ax3.text(*(route[n] + [0.0, 0.0, 0.02 * max(np.ptp(xyz[:, 2]), 0.1)]), pid, fontsize=8)
    _label_points(axy, route[:, 0], route[:, 1], route_ids)
    _side_view(axz, track_m, along, route_m, route_ids, route_kinds, entry)
    axz.set_xlabel("distance flown (km)")

    ax3.set_xlabel("x east (km)")
    ax3.set_ylabel("y north (km)")
    ax3.set_zlabel("z up (km)")
    ax3.set_title("3D view")
    ax3.view_init(elev=24, azim=-60)
    axy.set_xlabel("x east (km)")
    axy.set_ylabel("y north (km)")
    axy.set_title("plan view (route points labelled with their ids)")
    axy.grid(True, alpha=0.3)

    fig.legend(handles=_legend(), loc="outside lower center", ncol=4, fontsize=10, frameon=False)
    fig.suptitle(_title(plan, k, entry), fontsize=14)
    return _png(fig)


def _route_kinds(plan: dict, entry: dict) -> np.ndarray:
    """Kind letter of each route point, A first."""
    kinds = ["A"] + [str(leg.get("kind", "")) for leg in entry["legs"]]
    kinds[-1] = "B"
    return np.array(kinds)


def _legend() -> list[Line2D]:
    def marker(label: str, **kw) -> Line2D:
        return Line2D([], [], ls="", label=label, **kw)

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
        marker("other V points", marker="o", ms=4, mfc=COLOURS["V"], mec="none", alpha=0.5),
        marker("other H points", marker="^", ms=4, mfc=COLOURS["H"], mec="none", alpha=0.5),
        marker(
            "unreliable correction point (x when off route)",
            marker="o",
            ms=13,
            mfc="none",
            mec=UNRELIABLE,
            mew=1.6,
        ),
        marker("A (start)", marker="*", ms=15, mfc=COLOURS["A"], mec="black"),
        marker("B (end)", marker="s", ms=10, mfc=COLOURS["B"], mec="black"),
    ]


def error_budget_png(plan: dict, route_index: int | None = None) -> bytes:
    """The error budget of a route: vertical and horizontal error against distance flown, with
    each point's limits and the margin left on arrival, beside the plan and side views."""
    k, entry = route_entry(plan, route_index)
    legs = route_legs(entry)
    route_m = route_xyz(plan, entry, legs)
    track_m = trajectory_local(plan, k)
    ids, along = _route_stops(entry)
    kinds = _route_kinds(plan, entry)
    params = plan.get("parameters") or {}
    residual = float(params.get("fail_residual", 0.0))
    unreliable = [False] + [bool(leg.get("unreliable", False)) for leg in entry["legs"]]

    fig = plt.figure(figsize=(16, 10), layout="constrained")
    grid = fig.add_gridspec(3, 2, width_ratios=[1, 1.6])
    axy = fig.add_subplot(grid[:, 0])
    axz = fig.add_subplot(grid[0, 1])
    axv = fig.add_subplot(grid[1, 1], sharex=axz)
    axh = fig.add_subplot(grid[2, 1], sharex=axz)

    route = route_m / KM
    track = track_m / KM
    axy.plot(track[:, 0], track[:, 1], color=COLOURS["track"], lw=1.4)
    for letter in ("V", "H"):
        sel = kinds == letter
        axy.scatter(
            route[sel, 0],
            route[sel, 1],
            s=50,
            c=COLOURS[letter],
            marker="o" if letter == "V" else "^",
            edgecolors="black",
            zorder=3,
        )
    ring = np.array(unreliable)
    if ring.any():
        axy.scatter(route[ring, 0], route[ring, 1], s=200, fc="none", ec=UNRELIABLE, lw=1.5)
    axy.scatter(*route[0, :2], s=260, c=COLOURS["A"], marker="*", ec="k", zorder=4)
    axy.scatter(*route[-1, :2], s=120, c=COLOURS["B"], marker="s", ec="k", zorder=4)
    _label_points(axy, route[:, 0], route[:, 1], ids)
    axy.set_xlabel("x east (km)")
    axy.set_ylabel("y north (km)")
    axy.set_title("plan view")
    axy.set_aspect("equal", adjustable="datalim")
    axy.grid(True, alpha=0.3)

    _side_view(axz, track_m, along, route_m, ids, kinds, entry)
    for ax, component, resets in ((axv, "v", "V"), (axh, "h", "H")):
        _budget(ax, entry, along, kinds, component, resets, unreliable, residual)
    axh.set_xlabel("distance flown (km)")
    plt.setp(axz.get_xticklabels(), visible=False)
    plt.setp(axv.get_xticklabels(), visible=False)

    handles = [
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
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=10, frameon=False)
    fig.suptitle("error budget — " + _title(plan, k, entry), fontsize=14)
    return _png(fig)


def _budget(ax, entry: dict, along, kinds, component: str, resets: str, unreliable, residual):
    """One component's sawtooth: growth along each leg, the drop at each correcting point, the
    limit (a bar) and the margin (a band from the error up to the limit) at every point."""
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
    for n in range(1, len(x)):
        margin = limit[n] - arrival[n]
        ax.annotate(
            f"{margin:.2f}" if margin < 1 else f"{margin:.1f}",
            (x[n], limit[n]),
            xytext=(0, 5),
            textcoords="offset points",
            ha="center",
            fontsize=8,
            color=LIMIT if n == tight else "0.25",
            fontweight="bold" if n == tight else "normal",
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
    ax.set_ylim(0, top * 1.18)
    ax.set_title(
        f"{name} error: reset at {resets} points; limits and margins on arrival "
        f"(tightest {limit[tight] - arrival[tight]:.2f} at {entry['route'][tight]})",
        fontsize=11,
    )
    ax.grid(True, alpha=0.3)


def front_png(plan: dict) -> bytes:
    """The Pareto front: flown length against the number of corrections, coloured by the
    probability of arriving; readable with one route (said in words) and with fifty (labels
    only where they fit, routes below the plan's least probability drawn hollow)."""
    front = plan["front"]
    route_entry(plan)  # validates the plan and its chosen index
    chosen = int(plan.get("chosen", 0))
    corr = np.array([r.get("corrections", len(r["route"]) - 2) for r in front], dtype=float)
    length = np.array([r["length"] for r in front], dtype=float) / KM
    prob = np.array([r.get("probability", 1.0) for r in front], dtype=float)
    with_p = "probability" in (plan.get("objectives") or [])
    floor = float(plan.get("min_probability", 0.0) or 0.0)
    n = len(front)

    fig, ax = plt.subplots(figsize=(9, 6.5), layout="constrained")
    order = np.lexsort((length, corr))
    if not with_p and n > 1:  # with two objectives the front is a staircase worth a line
        ax.plot(corr[order], length[order], color="0.6", lw=1, zorder=1)
    size = 70 if n <= 20 else 40
    spread = with_p and prob.max() - prob.min() > 1e-9
    if spread:
        cmap = plt.get_cmap("viridis")
        norm = matplotlib.colors.Normalize(vmin=prob.min(), vmax=prob.max())
        colours = cmap(norm(prob))
        fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="P(arrive)")
    else:
        colours = np.tile(matplotlib.colors.to_rgba(COLOURS["V"]), (n, 1))
    safe = prob >= floor - 1e-12
    ax.scatter(
        corr[safe],
        length[safe],
        c=colours[safe],
        s=size,
        edgecolors="black",
        linewidths=0.6,
        zorder=2,
    )
    if (~safe).any():
        ax.scatter(
            corr[~safe],
            length[~safe],
            s=size,
            facecolors="none",
            edgecolors=colours[~safe],
            linewidths=1.6,
            zorder=2,
            label=f"P(arrive) below {floor:g}: not chosen by default",
        )
    if with_p and 1 < n <= 12:
        for c, L, pr in zip(corr, length, prob, strict=True):
            ax.annotate(
                f"P {pr:.3f}",
                (c, L),
                xytext=(8, -4),
                textcoords="offset points",
                fontsize=9,
                color="0.3",
            )
    # The chosen route is named in the legend, so that no label covers a point however many.
    text = f"chosen ({plan.get('choice', 'chosen')}): route {chosen}, "
    text += f"{corr[chosen]:.0f} corrections, {length[chosen]:.2f} km"
    if with_p:
        text += f", P(arrive) {prob[chosen]:.3f}"
    ax.scatter(
        corr[chosen],
        length[chosen],
        s=320,
        facecolors="none",
        edgecolors=COLOURS["B"],
        linewidths=2.2,
        zorder=3,
        label=text,
    )
    if n == 1:
        ax.text(
            0.03,
            0.97,
            "The front has one route: no other feasible route is shorter,\n"
            "needs fewer corrections" + (" or is likelier to arrive." if with_p else "."),
            transform=ax.transAxes,
            va="top",
            fontsize=11,
            color="0.25",
        )
    if n == 1:  # a lone point: show a sensible window around it, not a zero-width axis
        ax.set_xlim(corr[0] - 1.5, corr[0] + 4.5)
        ax.set_ylim(length[0] * 0.97, length[0] * 1.03)
    else:
        ax.margins(x=0.08, y=0.1)
    ax.set_xlabel("number of corrections")
    ax.set_ylabel("flown length (km)")
    ax.xaxis.get_major_locator().set_params(integer=True)
    ax.grid(True, alpha=0.3)
    fig.legend(loc="outside lower center", ncol=1, fontsize=10, frameon=False)
    scen = (plan.get("scenario") or {}).get("name", "scenario")
    ax.set_title(
        f"{scen}: Pareto front ({n} route{'' if n == 1 else 's'}; objectives: "
        f"{', '.join(plan.get('objectives') or ['length', 'corrections'])})"
    )
    return _png(fig)
