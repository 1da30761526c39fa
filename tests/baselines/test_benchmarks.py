"""The benchmark suite: its smoke run works end to end, and its plain comparator is exact.

The plain label search is only a fair yardstick if it answers the same question, so it is held
equal to brute force (and to the project's search) on many small random scenarios, including
the sparse ones where only walks that revisit a point are feasible.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from support.scenarios import corridor_scenario, mixed_scenario

from benchmarks import run as benchmarks_run
from benchmarks.fronts import compare
from benchmarks.paper import check_mapping, map_rows
from benchmarks.paper_routes import PAPER_ROUTES
from benchmarks.plain import plain_front, plain_search
from benchmarks.run import main
from benchmarks.worker import measure
from gcs_planner.baselines.brute import brute_force_front
from gcs_planner.core.route import evaluate_route
from gcs_planner.core.search import straight_front
from gcs_planner.scenario.generate import DATASET1, DATASET2
from gcs_planner.scenario.readers import load_scenario

TOL_M = 1e-6


def same_front(a, b) -> bool:
    return [k for _, k, _ in a] == [k for _, k, _ in b] and all(
        abs(x[0] - y[0]) <= TOL_M for x, y in zip(a, b)
    )


def project_front(scenario):
    return [(fp.length, fp.corrections, fp.points) for fp in straight_front(scenario).front]


def assert_valid(scenario, front) -> None:
    for length, k, route in front:
        evaluated = evaluate_route(scenario, route)
        assert evaluated.feasible and evaluated.simple
        assert abs(evaluated.length - length) <= TOL_M and evaluated.corrections == k


# --- the plain implementation is exact ------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 100_000), sparse=st.booleans())
def test_plain_front_equals_brute_force_and_project(seed: int, sparse: bool) -> None:
    scenario = corridor_scenario(seed) if sparse else mixed_scenario(seed)
    plain = plain_front(scenario)
    assert_valid(scenario, plain)
    assert same_front(plain, brute_force_front(scenario))
    assert same_front(plain, project_front(scenario))


# Corridor seeds (6 to 9 points) where the shortest walk revisits a point: the first pass finds
# a non-simple front and the visited-set pass must recover the simple one, or none.
@pytest.mark.parametrize("seed", [99, 585, 4142, 4275, 5426, 12145])
def test_plain_front_is_simple_where_walks_revisit(seed: int) -> None:
    scenario = corridor_scenario(seed) if seed < 1000 else corridor_scenario(seed, 6, 9)
    walks = plain_search(scenario, elementary=False)
    assert any(len(set(route)) < len(route) for _, _, route in walks)
    plain = plain_front(scenario)
    assert_valid(scenario, plain)
    assert same_front(plain, brute_force_front(scenario))
    assert same_front(plain, project_front(scenario))


# --- front comparison -------------------------------------------------------------------


def test_compare_gaps_found_and_missed() -> None:
    exact = [(100.0, 1, (0, 1, 9)), (90.0, 2, (0, 1, 2, 9))]
    # Best with <= 1 correction is 110 (10 % over 100); with <= 2 also 110 (22.2 % over 90).
    c = compare([(110.0, 1, (0, 3, 9))], exact)
    assert (c.found, c.missed, c.equal, c.beats_exact) == (0, 0, False, False)
    assert math.isclose(c.gap_max_pct, 20 / 0.9)
    assert math.isclose(c.gap_mean_pct, (10 + 20 / 0.9) / 2)
    c = compare([(90.0, 2, (0, 1, 2, 9))], exact)
    assert (c.found, c.missed, c.gap_max_pct) == (1, 1, 0.0)
    c = compare([], exact)
    assert c.missed == 2 and math.isnan(c.gap_mean_pct)
    assert compare(exact, exact).equal
    assert compare([(95.0, 1, (0, 4, 9))], exact).beats_exact


# --- the paper's routes -------------------------------------------------------------------


@pytest.mark.parametrize("spec", sorted(PAPER_ROUTES))
def test_paper_point_numbers_reproduce_the_printed_errors(spec, dataset_paths) -> None:
    params = {"dataset1": DATASET1, "dataset2": DATASET2}[spec]
    number = int(spec[-1])
    scenario = load_scenario(dataset_paths[number], params.to_dict())
    _, rows, reported = PAPER_ROUTES[spec]
    points = map_rows(scenario, rows)
    assert points[0] == scenario.start and points[-1] == scenario.end
    # Printed to 4 decimals: a wrong row would be off by kilometres of flight, i.e. units.
    assert check_mapping(scenario, rows) < 1e-4
    assert abs(evaluate_route(scenario, points).length - reported) < 1.0


# --- the entry point --------------------------------------------------------------------


def test_measure_kills_a_run_past_the_limit() -> None:
    # The plain search needs far more than 0.2 s on 5,000 points.
    assert measure("plain", "random-5000", 0.2, startup_s=3.0) is None
    done = measure("project", "small-12", 60.0)
    assert done is not None and done.rss_peak_mib >= done.rss_base_mib > 0
    assert len(done.front) >= 1


def test_quick_mode_writes_results_and_plot(tmp_path: Path, dataset_paths, monkeypatch) -> None:
    # Section 8 (start-up, whole processes) is the one section not run here: quick mode calls
    # startup_section(1, False), exactly what README's `python -m benchmarks` runs as
    # `--startup --runs 1 --warm-cache` in tests/docs/test_documented_commands.py
    # (test_documented_command[README.md:...]); run twice, it would start its six processes twice.
    calls: list[tuple[int, bool]] = []

    def start_up(runs: int, fresh_cache: bool = True) -> str:
        calls.append((runs, fresh_cache))
        return "## 8. Start-up: run by the documentation's test"

    monkeypatch.setattr(benchmarks_run, "startup_section", start_up)
    # `--quick` as users run it, its cases cut to the smallest that still run every section:
    # one scaling size (120: the smaller has no route; each method timed, compared, drawn),
    # one NSGA-II seed, two sweep cells (still two rounds and the separate cluster), a short
    # corridor. Each measurement is a fresh process, which is most of what this test costs.
    parse = benchmarks_run.parse

    def smallest(argv):
        cfg, profile_only, startup_only = parse(argv)
        assert cfg.sizes == [60, 120] and cfg.nsga_seeds == 2 and cfg.sweep_scenarios == 4
        small = replace(cfg, sizes=[120], nsga_seeds=1, sweep_scenarios=2, corridor_sizes=(200,))
        return small, profile_only, startup_only

    monkeypatch.setattr(benchmarks_run, "parse", smallest)
    main(["--quick", "--out", str(tmp_path)])
    assert calls == [(1, False)]
    text = (tmp_path / "RESULTS.md").read_text(encoding="utf-8")
    for heading in ("## 1.", "## 2.", "## 3.", "## 4.", "## 5.", "## 6.", "## 7.", "## 8.",
                    "## 9.", "## 10.", "Machine:"):  # fmt: skip
        assert heading in text
    assert "front = exact" in text
    assert "DIFFERS" not in text and "BEATS" not in text
    png = (tmp_path / "scaling.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
