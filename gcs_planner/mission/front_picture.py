"""The Pareto front picture: flown length against the number of corrections, the chosen route
highlighted and the probability of arriving as colour when the plan has it; it reads with one
route and with fifty."""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.ticker import MaxNLocator

from gcs_planner.mission.picture_axes import COLOURS, DPI, KM, plt, to_png
from gcs_planner.mission.picture_labels import Label, LabelPlacer, left_out, marker_radius
from gcs_planner.mission.plan_reading import route_entry


def front_figure(plan: dict) -> Figure:
    """The Pareto front: flown length against the number of corrections (integer ticks),
    coloured by the probability of arriving; readable with one route (said in words) and with
    fifty (labels only where they fit, routes below the plan's least probability drawn
    hollow)."""
    front = plan["front"]
    route_entry(plan)  # validates the plan and its chosen index
    chosen = int(plan.get("chosen", 0))
    corr = np.array([r.get("corrections", len(r["route"]) - 2) for r in front], dtype=float)
    length = np.array([r["length"] for r in front], dtype=float) / KM
    prob = np.array([r.get("probability", 1.0) for r in front], dtype=float)
    with_p = "probability" in (plan.get("objectives") or [])
    floor = float(plan.get("min_probability", 0.0) or 0.0)
    n = len(front)

    fig, ax = plt.subplots(figsize=(9, 6.5), layout="constrained", dpi=DPI)
    order = np.lexsort((length, corr))
    if not with_p and n > 1:  # with two objectives the front is a staircase worth a line
        ax.plot(corr[order], length[order], color="0.6", lw=1, zorder=1)
    size = 70 if n <= 20 else 40
    colours = _route_colours(fig, ax, prob, with_p)
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
    _mark_chosen(ax, plan, corr, length, prob, with_p)
    note = _one_route_note(ax, with_p) if n == 1 else None
    _count_axis(ax, corr, length)
    fig.legend(loc="outside lower center", ncol=1, fontsize=10, frameon=False)
    scen = (plan.get("scenario") or {}).get("name", "scenario")
    ax.set_title(
        f"{scen}: Pareto front ({n} route{'' if n == 1 else 's'}; objectives: "
        f"{', '.join(plan.get('objectives') or ['length', 'corrections'])})"
    )
    placer = LabelPlacer(fig)
    if note is not None:
        placer.reserve(note)
    if with_p and 1 < n <= 12:
        pts = np.column_stack([corr, length])
        labels = [
            Label(f"P {pr:.3f}", tuple(pt), size=9, colour="0.3", clearance=marker_radius(size))
            for pt, pr in zip(pts, prob, strict=True)
        ]
        markers = [(pts, marker_radius(size)), (pts[chosen : chosen + 1], marker_radius(320))]
        left_out(ax, placer.place(ax, labels, markers))
    return fig


def _route_colours(fig: Figure, ax: Axes, prob: np.ndarray, with_p: bool) -> np.ndarray:
    """(n, 4) RGBA of each route: its probability of arriving on a colour bar when the plan
    has that objective and the routes differ in it, else one colour."""
    if with_p and prob.max() - prob.min() > 1e-9:
        cmap = plt.get_cmap("viridis")
        norm = matplotlib.colors.Normalize(vmin=prob.min(), vmax=prob.max())
        fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="P(arrive)")
        return cmap(norm(prob))
    return np.tile(matplotlib.colors.to_rgba(COLOURS["V"]), (len(prob), 1))


def _mark_chosen(
    ax: Axes, plan: dict, corr: np.ndarray, length: np.ndarray, prob: np.ndarray, with_p: bool
) -> None:
    """Ring the chosen route. It is named in the legend, so that no label covers a point however
    many."""
    chosen = int(plan.get("chosen", 0))
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


def _one_route_note(ax: Axes, with_p: bool) -> Text:
    """What a front of one route means, in words."""
    return ax.text(
        0.03,
        0.97,
        "The front has one route: no other feasible route is shorter,\n"
        "needs fewer corrections" + (" or is likelier to arrive." if with_p else "."),
        transform=ax.transAxes,
        va="top",
        fontsize=11,
        color="0.25",
    )


def _count_axis(ax: Axes, corr: np.ndarray, length: np.ndarray) -> None:
    """The axes' window, ticks, labels and grid: corrections as a count axis."""
    if len(corr) == 1:  # a lone point: show a sensible window around it, not a zero-width axis
        ax.set_xlim(corr[0] - 1.5, corr[0] + 4.5)
        pad = max(abs(length[0]) * 0.03, 0.05)  # km; a 0 km route still gets a window
        ax.set_ylim(length[0] - pad, length[0] + pad)
    else:
        # A count axis: integer ticks, over at least three whole numbers (a narrower window
        # would leave MaxNLocator only fractional ticks).
        lo, hi = corr.min(), corr.max()
        pad = max(0.5, 0.08 * (hi - lo))
        lo, hi = lo - pad, hi + pad
        if hi - lo < 3:
            mid = (hi + lo) / 2
            lo, hi = mid - 1.5, mid + 1.5
        ax.set_xlim(lo, hi)
        ax.margins(y=0.1)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("number of corrections")
    ax.set_ylabel("flown length (km)")
    ax.grid(True, alpha=0.3)


def front_png(plan: dict) -> bytes:
    """``front_figure`` as PNG bytes."""
    return to_png(front_figure(plan))
