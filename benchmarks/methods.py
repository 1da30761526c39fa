"""Section 1: the methods side by side on the same scenarios, straight legs, two objectives."""

from __future__ import annotations

import statistics
from dataclasses import dataclass

from benchmarks.fronts import Comparison, compare
from benchmarks.report import seconds, table
from benchmarks.worker import Measurement, measure


@dataclass(frozen=True)
class Settings:
    runs: int
    time_limit: float
    nsga_seeds: int
    nsga_budget: float


@dataclass
class Row:
    scenario: str
    method: str
    front: str  # the method's front as "length m / k"
    comparison: Comparison | None
    seconds: float | None  # median; None: did not finish within the limit
    ratio: float | None  # seconds / the project's seconds
    note: str = ""


def _front_text(front) -> str:
    return "; ".join(f"{length:,.1f}/{k}" for length, k, _ in front) or "none"


def _median_runs(method: str, spec: str, s: Settings) -> tuple[Measurement | None, float | None]:
    """First run's measurement and the median time of ``s.runs`` runs (None past the limit)."""
    runs = []
    for _ in range(s.runs):
        m = measure(method, spec, s.time_limit)
        if m is None:
            return None, None
        runs.append(m)
    return runs[0], statistics.median(r.seconds for r in runs)


def run_methods(specs: list[str], s: Settings) -> list[Row]:
    rows: list[Row] = []
    for spec in specs:
        exact, t_exact = _median_runs("project", spec, s)
        if exact is None:
            rows.append(Row(spec, "project", "", None, None, None, "> limit"))
            continue
        rows.append(
            Row(
                spec,
                "project (exact)",
                _front_text(exact.front),
                compare(exact.front, exact.front),
                t_exact,
                1.0,
            )
        )
        for method in ("plain", "milp"):
            m, t = _median_runs(method, spec, s)
            if m is None:
                rows.append(Row(spec, method, "", None, None, None, f"> {s.time_limit:g} s"))
                continue
            c = compare(m.front, exact.front)
            note = m.note or ("front = exact" if c.equal else "FRONT DIFFERS from exact")
            if c.beats_exact:
                note += "; BEATS THE EXACT FRONT (a bug in one of them)"
            rows.append(Row(spec, method, _front_text(m.front), c, t, t / t_exact, note))
        rows.append(_nsga2_row(spec, exact, t_exact, s))
    return rows


def _nsga2_row(spec: str, exact: Measurement, t_exact: float, s: Settings) -> Row:
    per_seed = []
    for seed in range(s.nsga_seeds):
        # The budget ends the run; the limit only guards against a hang.
        m = measure("nsga2", spec, s.nsga_budget * 3 + 30, seed=seed, budget=s.nsga_budget)
        if m is None:
            continue
        per_seed.append((m, compare(m.front, exact.front)))
    if not per_seed:
        return Row(spec, "NSGA-II", "", None, None, None, "no seed finished")
    med = statistics.median
    # The median seed by mean gap stands for the front; the numbers are medians over seeds.
    by_gap = sorted(per_seed, key=lambda mc: (mc[1].missed, _nan_last(mc[1].gap_mean_pct)))
    typical_m, typical_c = by_gap[(len(by_gap) - 1) // 2]
    c = Comparison(
        typical_c.exact_points,
        int(med(c.found for _, c in per_seed)),
        int(med(c.missed for _, c in per_seed)),
        med(_nan_last(c.gap_max_pct) for _, c in per_seed),
        med(_nan_last(c.gap_mean_pct) for _, c in per_seed),
        all(c.equal for _, c in per_seed),
        any(c.beats_exact for _, c in per_seed),
    )
    t = med(m.seconds for m, _ in per_seed)
    gens = med(m.extra.get("generations", 0) for m, _ in per_seed)
    equal = sum(c.equal for _, c in per_seed)
    note = (
        f"pop 100, {s.nsga_budget:g} s budget, seeds 0–{s.nsga_seeds - 1} "
        f"(medians; {equal}/{len(per_seed)} seeds found the exact front; "
        f"median {gens:g} generations)"
    )
    if c.beats_exact:
        note += "; BEATS THE EXACT FRONT (a bug in one of them)"
    return Row(spec, "NSGA-II", _front_text(typical_m.front), c, t, t / t_exact, note)


def _nan_last(x: float) -> float:
    return float("inf") if x != x else x


def render(rows: list[Row]) -> str:
    header = (
        "scenario",
        "method",
        "front (m / corrections)",
        "exact points found",
        "missed",
        "gap max %",
        "gap mean %",
        "time (median)",
        "× project",
        "note",
    )
    out = []
    for r in rows:
        c = r.comparison
        found = f"{c.found}/{c.exact_points}" if c else "–"
        out.append(
            (
                r.scenario,
                r.method,
                r.front or "–",
                found,
                c.missed if c else None,
                _gap(c.gap_max_pct) if c else None,
                _gap(c.gap_mean_pct) if c else None,
                seconds(r.seconds) if r.seconds is not None else r.note,
                f"{r.ratio:,.1f}×" if r.ratio is not None else None,
                r.note if r.seconds is not None else "",
            )
        )
    return table(header, out)


def _gap(x: float) -> str:
    if x != x or x == float("inf"):
        return "–"
    return f"{x:.3f}"
