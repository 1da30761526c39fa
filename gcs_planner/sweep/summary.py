"""The summary picture: how the front moves with the swept parameter.

Left: the length of each cell's shortest front route against the swept value, as a change in
per cent from the same scenario at the first swept value (scenarios differ by kilometres, a
parameter moves the front by metres: absolute lengths would hide the effect looked for); one
line per scenario, or a median and a 10-90 % band when there are many. Right: how many
corrections the chosen route needs. Failed and infeasible cells are counted in the title, since
a point that is missing from a line is itself a finding.
"""

from __future__ import annotations

import io
import statistics
from collections import defaultdict
from pathlib import Path

from gcs_planner.runtime.atomic import write_atomic

# Beyond this many scenarios, individual lines become noise: show the median and a band.
MAX_LINES = 12


def summary_png(rows: list[dict], swept: tuple[str, ...], out: Path, title: str) -> Path:
    """Draw the summary of ``rows`` against the first swept parameter into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    axis = next((k for k in swept), None)
    ok = [r for r in rows if r["status"] == "ok"]
    failed = len({r["cell_key"] for r in rows if r["status"] == "error"})
    infeasible = len({r["cell_key"] for r in rows if r["status"] == "infeasible"})

    # Per cell: the shortest front route's length and the chosen route's corrections.
    cells: dict[str, dict] = {}
    for r in ok:
        c = cells.setdefault(r["cell_key"], {"row": r, "length": r["length"], "corr": None})
        c["length"] = min(c["length"], r["length"])
        if r["chosen"]:
            c["corr"] = r["corrections"]

    def x_of(row: dict) -> object:
        if axis is None:
            return "all"
        value = row.get(axis)
        return value if value is not None else "-"

    xs = sorted({x_of(c["row"]) for c in cells.values()}, key=_order)
    numeric = all(isinstance(x, (int, float)) for x in xs) and axis is not None
    position = {x: (x if numeric else i) for i, x in enumerate(xs)}
    # A line per scenario and per combination of the other swept values.
    series: dict[str, dict[object, tuple[float, int | None]]] = defaultdict(dict)
    for c in cells.values():
        r = c["row"]
        others = ", ".join(f"{k}={_show(r.get(k))}" for k in swept[1:])
        label = r["scenario"] + (f" ({others})" if others else "")
        series[label][x_of(r)] = (c["length"], c["corr"])
    # Lengths as per cent change from the series' first swept value that has a route.
    for points in series.values():
        first = points[min(points, key=_order)][0]
        for x, (length, corr) in points.items():
            points[x] = (100.0 * (length - first) / first, corr)

    fig, (ax_len, ax_corr) = plt.subplots(1, 2, figsize=(13, 4.8))
    if len(series) <= MAX_LINES:
        # A colour per scenario, a line style per combination of the other swept values: the
        # lines of one scenario often coincide, and a dashed line over a solid one still shows.
        scenarios = sorted({label.split(" (")[0] for label in series})
        variants = sorted({label.partition(" (")[2] for label in series})
        styles = ("-", "--", ":", "-.")
        for label, points in sorted(series.items()):
            keys = sorted(points, key=_order)
            px = [position[k] for k in keys]
            scenario, _, variant = label.partition(" (")
            look = {
                "color": f"C{scenarios.index(scenario) % 10}",
                "linestyle": styles[variants.index(variant) % len(styles)],
                "marker": "o",
                "label": label,
            }
            ax_len.plot(px, [points[k][0] for k in keys], **look)
            ax_corr.plot(px, [points[k][1] for k in keys], **look)
        fig.legend(*ax_len.get_legend_handles_labels(), loc="center right", fontsize="small")
    else:
        for ax, which in ((ax_len, 0), (ax_corr, 1)):
            mids, lows, highs, px = [], [], [], []
            for x in xs:
                values = sorted(
                    p[x][which] for p in series.values() if x in p and p[x][which] is not None
                )
                if not values:
                    continue
                px.append(position[x])
                mids.append(statistics.median(values))
                lows.append(_quantile(values, 0.1))
                highs.append(_quantile(values, 0.9))
            ax.plot(px, mids, marker="o", label=f"median of {len(series)} scenarios")
            ax.fill_between(px, lows, highs, alpha=0.25, label="10-90 %")
            ax.legend(fontsize="small")
    ax_corr.yaxis.set_major_locator(MaxNLocator(integer=True))
    label = axis or "(nothing swept: all cells)"
    for ax in (ax_len, ax_corr):
        ax.set_xlabel(label)
        ax.grid(alpha=0.3)
        if not numeric:
            ax.set_xticks(range(len(xs)), [str(x) for x in xs])
    first = f"{axis}={xs[0]}" if axis is not None and xs else "the first cell"
    ax_len.set_ylabel(f"shortest front route: change from {first} (%)")
    ax_corr.set_ylabel("corrections of the chosen route")
    fig.suptitle(f"{title}: {len(cells)} cells planned, {infeasible} infeasible, {failed} failed")
    # Fixed margins, not tight_layout: it lays the figure out by drawing it once more, which
    # doubled the picture's cost (some 0.5 s a sweep on this machine), paid after the last cell.
    legend_room = 0.76 if len(series) <= MAX_LINES else 0.99
    fig.subplots_adjust(left=0.065, right=legend_room, bottom=0.11, top=0.9, wspace=0.22)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return write_atomic(out, buffer.getvalue())


def _show(value: object) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def _order(value: object) -> tuple:
    if isinstance(value, (int, float)):
        return (0, value, "")
    return (1, 0, str(value))


def _quantile(sorted_values: list[float], q: float) -> float:
    index = q * (len(sorted_values) - 1)
    low = int(index)
    high = min(low + 1, len(sorted_values) - 1)
    return sorted_values[low] + (sorted_values[high] - sorted_values[low]) * (index - low)
