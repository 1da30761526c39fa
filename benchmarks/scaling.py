"""Section 2: time and peak memory against the number of points, and the plot."""

from __future__ import annotations

import statistics
from dataclasses import dataclass
from pathlib import Path

from benchmarks.fronts import compare
from benchmarks.report import seconds, table
from benchmarks.worker import measure

SCALING_METHODS = ("project", "project-numpy", "plain", "milp")
LABELS = {
    "project": "project (exact; numba kernels from 3,000 points)",
    "project-numpy": "project, numpy engine only",
    "plain": "plain (pure Python)",
    "milp": "MILP",
}


@dataclass
class Point:
    method: str
    n: int
    seconds: float | None  # median; None: past the limit (or skipped after a smaller size was)
    rss_own_mib: float | None  # peak RSS above the child's baseline, largest over the runs
    rss_peak_mib: float | None
    front: str = ""
    note: str = ""


def run_scaling(
    sizes: list[int], runs: int, time_limit: float, project_limit: float | None
) -> list[Point]:
    """Every method on ``random-N`` for each size, ``runs`` fresh children each. A method that
    passes the limit at one size is not run at larger ones (its cost only grows with n).
    The project's own search runs under ``project_limit`` (None: no limit)."""
    points: list[Point] = []
    exact_fronts: dict[int, list] = {}
    for method in SCALING_METHODS:
        limit = project_limit if method == "project" else time_limit
        over = None
        for n in sorted(sizes):
            if over is not None:
                points.append(Point(method, n, None, None, None, note=f"> limit at {over}"))
                continue
            got = []
            for _ in range(runs):
                m = measure(method, f"random-{n}", limit)
                if m is None:
                    break
                got.append(m)
            if len(got) < runs:
                over = n
                points.append(Point(method, n, None, None, None, note=f"> {limit:g} s"))
                continue
            front = got[0].front
            note = got[0].note
            if method == "project":
                exact_fronts[n] = front
            elif n in exact_fronts:
                same = compare(front, exact_fronts[n]).equal
                note = note or ("front = exact" if same else "FRONT DIFFERS from exact")
            points.append(
                Point(
                    method,
                    n,
                    statistics.median(m.seconds for m in got),
                    max(m.rss_own_mib for m in got),
                    max(m.rss_peak_mib for m in got),
                    "; ".join(f"{length:,.0f}/{k}" for length, k, _ in front) or "none",
                    note,
                )
            )
    return points


def render(points: list[Point]) -> str:
    project = {p.n: p.seconds for p in points if p.method == "project"}
    rows = []
    for p in points:
        base = project.get(p.n)
        ratio = p.seconds / base if p.seconds is not None and base else None
        rows.append(
            (
                p.n,
                LABELS[p.method],
                seconds(p.seconds) if p.seconds is not None else p.note,
                f"{ratio:,.1f}×" if ratio is not None else None,
                f"{p.rss_own_mib:,.1f}" if p.rss_own_mib is not None else None,
                f"{p.rss_peak_mib:,.0f}" if p.rss_peak_mib is not None else None,
                p.front or "–",
                p.note if p.seconds is not None else "",
            )
        )
    header = (
        "points",
        "method",
        "time (median)",
        "× project",
        "peak MiB above baseline",
        "peak RSS MiB",
        "front (m / corrections)",
        "note",
    )
    return table(header, rows)


def plot(points: list[Point], path: Path) -> None:
    """Time and peak memory against points, log-log, one line per method."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(11, 4.2))
    for method in SCALING_METHODS:
        done = [p for p in points if p.method == method and p.seconds is not None]
        if not done:
            continue
        n = [p.n for p in done]
        ax_t.plot(n, [p.seconds for p in done], "o-", label=LABELS[method])
        # A log axis cannot show 0: a run whose peak did not rise above the baseline is drawn
        # at the resolution of ru_maxrss, 4 KiB.
        ax_m.plot(n, [max(p.rss_own_mib, 4 / 1024) for p in done], "o-", label=LABELS[method])
    for ax, title, unit in (
        (ax_t, "time (median of runs)", "seconds"),
        (ax_m, "peak memory above the process baseline", "MiB"),
    ):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("points in the scenario")
        ax.set_ylabel(unit)
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
