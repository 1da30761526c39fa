"""The benchmark suite: the project's exact search against NSGA-II, a MILP and a plain label
search; scaling with the number of points; turns and uncertain corrections; the paper's routes;
mission upload over loopback; sweeps on Dask against a serial loop; the mock vehicle flying the
longest front route; long corridors with three objectives.

    python -m benchmarks                       # the full run (tens of minutes)
    python -m benchmarks --quick               # smoke run in seconds (CI)
    python -m benchmarks --profile             # cProfile of straight_front only

Writes RESULTS.md (markdown tables with the machine they were measured on) and scaling.png into
``--out`` and prints the tables. Timings are medians of ``--runs`` runs; each (method, scenario,
run) of sections 1 and 2 is a fresh process, killed at ``--time-limit``.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from benchmarks import (
    corridors,
    flight,
    flyable,
    methods,
    paper,
    profiling,
    scaling,
    startup,
    turns,
    upload,
)
from benchmarks import sweep as sweep_bench
from benchmarks.cases import DATA, DATASETS, valid_spec
from benchmarks.report import machine
from gcs_planner.runtime.atomic import write_atomic

DEFAULT_OUT = Path(__file__).resolve().parent / "results"
COMMAND = "python -m benchmarks"


@dataclass(frozen=True)
class Config:
    scenarios: list[str]
    paper_scenarios: list[str]
    sizes: list[int]
    runs: int
    time_limit: float
    project_limit: float | None
    nsga_seeds: int
    nsga_budget: float
    out: Path
    command: str
    upload_items: int = 1000
    # Start-up timed from a fresh numba cache, as a first plan leaves it (the protocol);
    # False: the cache as it is (smoke runs).
    fresh_cache: bool = True
    sweep_scenarios: int = 200
    sweep_corrections: int = sweep_bench.CORRECTIONS
    corridor_sizes: tuple[int, ...] = (3000, 20000)
    corridor_limit: float = 120.0  # seconds per corridor plan


def parse(argv: list[str] | None) -> tuple[Config, bool, bool]:
    ap = argparse.ArgumentParser(
        prog=COMMAND,
        description="Benchmarks of the exact search against NSGA-II, a MILP and a plain search.",
    )
    ap.add_argument("--runs", type=int, default=3, help="runs per measurement (median)")
    ap.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=[300, 1500, 5000, 20000],
        help="correction points of the random scaling scenarios",
    )
    ap.add_argument(
        "--time-limit",
        type=float,
        default=120.0,
        help="seconds per run of the plain search and the MILP (killed after)",
    )
    ap.add_argument(
        "--project-limit",
        type=float,
        default=None,
        help="seconds per run of the project's search (default: none)",
    )
    ap.add_argument("--nsga-seeds", type=int, default=5)
    ap.add_argument("--nsga-budget", type=float, default=10.0, help="seconds per NSGA-II run")
    ap.add_argument(
        "--scenarios",
        nargs="+",
        default=None,
        help="scenarios of sections 1 and 3 (dataset1 dataset2 random-N small-N)",
    )
    ap.add_argument("--quick", action="store_true", help="smoke run: tiny sizes, 1 run, seconds")
    ap.add_argument(
        "--profile",
        action="store_true",
        help="only profile straight_front (dataset 1, 5,000 points) and print it",
    )
    ap.add_argument(
        "--startup",
        action="store_true",
        help="only time the command line's start (section 6) and print it",
    )
    ap.add_argument(
        "--warm-cache",
        action="store_true",
        help="time the start-up with numba's cache as it is, not as a first plan leaves a fresh "
        "one (a smoke run; --quick implies it)",
    )
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args(argv)
    if min(args.runs, args.nsga_seeds) < 1 or args.time_limit <= 0 or args.nsga_budget <= 0:
        ap.error("--runs and --nsga-seeds must be >= 1, --time-limit and --nsga-budget > 0")
    if min(args.sizes) < 1:
        ap.error("--sizes must be >= 1")
    for spec in args.scenarios or []:
        if not valid_spec(spec):
            ap.error(
                f"unknown scenario {spec!r}: dataset1, dataset2, random-N, small-N or corridor-N"
            )
    workbooks = ["dataset1", "dataset2"]
    if args.quick:
        cfg = Config(
            scenarios=args.scenarios or ["small-12"],
            paper_scenarios=["dataset2"],
            sizes=[60, 120],
            runs=1,
            time_limit=min(args.time_limit, 20.0),
            project_limit=20.0,
            nsga_seeds=2,
            nsga_budget=0.3,
            out=args.out,
            command=f"{COMMAND} --quick",
            upload_items=100,
            sweep_scenarios=4,
            sweep_corrections=40,
            corridor_sizes=(600,),
            corridor_limit=2.0,
            fresh_cache=False,
        )
    else:
        cfg = Config(
            scenarios=args.scenarios or workbooks,
            paper_scenarios=workbooks,
            sizes=args.sizes,
            runs=args.runs,
            time_limit=args.time_limit,
            project_limit=args.project_limit,
            nsga_seeds=args.nsga_seeds,
            nsga_budget=args.nsga_budget,
            out=args.out,
            command=" ".join([COMMAND, *(argv if argv is not None else sys.argv[1:])]),
            corridor_limit=args.time_limit,
            fresh_cache=not args.warm_cache,
        )
    return cfg, args.profile, args.startup


def run(cfg: Config) -> str:
    """Run every section and return RESULTS.md's text; writes the plot on the way."""
    started = time.perf_counter()
    where = machine()
    print(f"machine: {where}", flush=True)
    s = methods.Settings(cfg.runs, cfg.time_limit, cfg.nsga_seeds, cfg.nsga_budget)
    sections = []

    print("1. methods side by side ...", flush=True)
    rows = methods.run_methods(cfg.scenarios, s)
    sections.append(
        "## 1. Methods side by side (straight legs; length and corrections)\n\n"
        f"Exact front: the project's `straight_front`. Per exact front point (L*, k) each method's "
        f'shortest route with at most k corrections; gap = (L − L*)/L*; "missed": no route with '
        f"at most k corrections. Times are medians of {cfg.runs} runs, each in a fresh process "
        f"(imports and scenario loading not timed); plain and MILP are killed after "
        f"{cfg.time_limit:g} s (the MILP's time limit per solve is the same). NSGA-II: population "
        f"100, a fixed budget of {cfg.nsga_budget:g} s per run, seeds 0–{cfg.nsga_seeds - 1}, "
        f"medians over the seeds.\n\n" + methods.render(rows)
    )
    print(sections[-1], flush=True)

    print("2. scaling ...", flush=True)
    points = scaling.run_scaling(cfg.sizes, cfg.runs, cfg.time_limit, cfg.project_limit)
    png = cfg.out / "scaling.png"
    scaling.plot(points, png)
    sections.append(
        "## 2. Scaling with the number of points\n\n"
        "Scenarios `random_scenario(n, seed=1, params=DATASET1)` (n correction points in the "
        "contest's 100 × 100 × 10 km box). Time: median of "
        f"{cfg.runs} runs; peak memory: the child's peak RSS (`getrusage`) and how far it rose "
        "above the child's baseline after imports and scenario generation (largest over the "
        f"runs). Plain and MILP are killed after {cfg.time_limit:g} s and not run at larger "
        "sizes; the project's search "
        + (f"after {cfg.project_limit:g} s." if cfg.project_limit else "runs without a limit.")
        + "\n\n"
        + scaling.render(points)
        + f"\n\n![time and peak memory against points]({png.name})"
    )
    print(sections[-1], flush=True)

    print("3. turns and uncertain corrections ...", flush=True)
    trows = turns.run_turns(cfg.scenarios, cfg.runs)
    sections.append(
        f"## 3. Every mode: straight legs and turns (R = {turns.TURN_RADIUS:g} m), two and "
        "three objectives, heading at A free or given\n\n"
        "`plan(scenario, objectives=...)` in this process with the default budget, median of "
        f'{cfg.runs} runs. Proof: "proven" (the exact front), or the largest gap between a '
        "front route's length and its proven lower bound, how many routes are settled (their "
        '"optimal" flag holds: no open partial route may still add a route with no more '
        "corrections or a higher probability) and the length below which the front is "
        "complete.\n\n" + turns.render(trows)
    )
    print(sections[-1], flush=True)

    print("4. the paper's routes ...", flush=True)
    lines, checks = paper.run_paper(cfg.paper_scenarios)
    sections.append(
        "## 4. The paper's routes re-evaluated (Tables 3 and 4)\n\n"
        "Each paper route with straight legs (`evaluate_route`) and flown with turns of "
        f"R = {paper.TURN_RADIUS:g} m (`flown_route`), under the dataset's own limits; success "
        "probability with p = 0.8, residual 5 at the flagged points (`success_probability`). "
        "Beside it the shortest route of the exact straight front with no more corrections, and "
        "the planner's front with turns.\n\n" + paper.render(lines, checks)
    )
    print(sections[-1], flush=True)

    print("5. upload ...", flush=True)
    items = cfg.upload_items
    sections.append(
        "## 5. Mission upload over loopback\n\n"
        f"The project's client uploads a {items:,}-item mission to the mock vehicle over UDP "
        "127.0.0.1 and reads it back to verify it (`benchmarks.upload.benchmark_upload`), no "
        "faults; "
        f"medians of {cfg.runs} runs.\n\n" + upload.render(upload.run_upload(items, cfg.runs))
    )
    print(sections[-1], flush=True)

    print("6. flyable routes ...", flush=True)
    frows = flyable.run_flyable(cfg.scenarios, 1)
    sections.append(
        "## 6. Flyable routes: airplane legs under climb limits\n\n"
        "`plan(scenario, objectives=...)`, one run each: straight legs, the tilted-plane cs3d "
        f"leg and airplane legs (R = {flyable.TURN_RADIUS:g} m; horizontal turns, a constant "
        "flight-path angle within the limits, helices where a leg is too steep). The shortest "
        "route of each front against the straight-leg front's, the shortest route certain to "
        "arrive, the steepest leg of any front route and the helix turns the front flies. "
        "Proof: 'proven' is an exhausted search; otherwise the largest gap between a front "
        "route and its proven lower bound, how many routes are unsettled and below which length "
        "the front is complete (default budget: no label limit, 60 s).\n\n" + flyable.render(frows)
    )
    print(sections[-1], flush=True)

    print("7. sweeps on Dask ...", flush=True)
    n, k = cfg.sweep_scenarios, cfg.sweep_corrections
    timings, ratios = sweep_bench.run_benchmark(n, k, rounds=2 if n < 10 else 8)
    sections.append(
        "## 7. Sweeps on Dask against a serial loop\n\n"
        "The same cells (`gcs_planner.sweep.run_cell`) in a loop in one process, on the local "
        "cluster `gcs-planner sweep` starts (2 worker processes, 1 thread each), and on a "
        "`dask scheduler` with `dask worker` processes started separately (`benchmarks/sweep.py`)."
        "\n\n" + sweep_bench.render(timings, ratios, n, k, 200.0)
    )
    print(sections[-1], flush=True)

    print("8. start-up ...", flush=True)
    sections.append(startup_section(cfg.runs, cfg.fresh_cache))
    print(sections[-1], flush=True)

    print("9. flight ...", flush=True)
    sections.append(
        "## 9. The mock vehicle flies the longest front route\n\n"
        "Front (length, corrections), R = 200 m, exported with the dry run's 1 m acceptance "
        "radius; `sim.replay.replay` (flight model and autopilot, then the INS along the flown "
        "track) against the chord replay it replaced (items joined by straight segments), "
        f"medians of {cfg.runs} runs in this process.\n\n"
        + flight.render(flight.run_flight(cfg.scenarios, cfg.runs))
    )
    print(sections[-1], flush=True)

    print("10. long corridors ...", flush=True)
    sections.append(
        "## 10. Long corridors: straight legs, three objectives\n\n"
        "`plan(load_case('corridor-N'), objectives=(length, corrections, probability), "
        f"time_limit={cfg.corridor_limit:g})`, one run each, no label limit (the default): N "
        "points in a 300 × 20 × 2 km corridor (`benchmarks/corridors.py`). Proof as in section "
        "3; the fewest-corrections end of the front against the two-objective front's, which the "
        "three-objective front must contain.\n\n"
        + corridors.render(corridors.run_corridors(list(cfg.corridor_sizes), cfg.corridor_limit))
    )
    print(sections[-1], flush=True)

    took = time.perf_counter() - started
    head = (
        "# Benchmark results\n\n"
        f"Regenerate with `{cfg.command}` (from the repository root, with the contest workbooks "
        f"in `../shared/data/gmcm2019f` beside the repository).\n\n"
        f"Machine: {where}. The whole run took {took / 60:,.1f} min.\n"
    )
    return "\n\n".join([head, *sections]) + "\n"


def startup_section(runs: int, fresh_cache: bool = True) -> str:
    return (
        "## 8. Start-up: the command line as whole processes\n\n"
        "Each row a fresh process (`python -m gcs_planner`, what the installed script runs), "
        f"medians of {runs} interleaved rounds; the floor is a bare "
        "`python -c 'import numpy, scipy.spatial'` measured in the same rounds. \"Above floor + "
        'search" is what start-up, reading the scenario and writing the JSON add; CPU time '
        "(user + system) is steadier than wall time on a shared machine.\n\n"
        + (
            "numba's cache filled as a first plan fills it.\n\n"
            if fresh_cache
            else "numba's cache as it was (`--warm-cache`).\n\n"
        )
        + startup.render(startup.run_startup(runs, fresh_cache))
    )


def main(argv: list[str] | None = None) -> None:
    cfg, profile_only, startup_only = parse(argv)
    if profile_only:
        print(profiling.profile())
        return
    if startup_only:
        print(startup_section(cfg.runs, cfg.fresh_cache))
        return
    needed = {spec for spec in [*cfg.scenarios, *cfg.paper_scenarios] if spec in DATASETS}
    missing = [str(DATA / f"{spec}.xlsx") for spec in sorted(needed)]
    missing = [path for path in missing if not Path(path).exists()]
    if missing:
        sys.exit(f"error: {', '.join(missing)} not found: ../shared must be beside the repository")
    text = run(cfg)
    cfg.out.mkdir(parents=True, exist_ok=True)
    write_atomic(cfg.out / "RESULTS.md", text)
    print(f"wrote {cfg.out / 'RESULTS.md'} and {cfg.out / 'scaling.png'}")


if __name__ == "__main__":
    main()
