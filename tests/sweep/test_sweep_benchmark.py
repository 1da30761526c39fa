"""The sweep benchmark's smoke run: serial loop, local cluster and a separately started
`dask scheduler` / `dask worker` give the same fronts (run_benchmark raises if they differ)."""

from __future__ import annotations

from benchmarks import sweep as sweep_bench


def test_sweep_benchmark_runs_all_three_ways_with_equal_fronts(tmp_path) -> None:
    # 100 corrections: of the 4 generated scenarios two have routes and two have none, so the
    # fronts compared hold lengths and routes, not only "infeasible" (as at 40 corrections).
    spec = tmp_path / "spec.toml"
    spec.write_text(sweep_bench.spec_text(4, 100, 200.0), "utf-8")
    statuses = sorted(f[0][0] for f in sweep_bench._serial(spec)[2].values())
    assert statuses == ["infeasible", "infeasible", "ok", "ok"]
    # One worker: the fronts are the subject, not the speed-up (each worker process of the
    # separately started `dask worker` imports the planner afresh).
    timings, ratios = sweep_bench.run_benchmark(4, corrections=100, workers=1, rounds=2)
    assert [t.cells for t in timings] == [4, 4, 4] and len(ratios) == 2
    assert "serial" in timings[0].name and "local cluster" in timings[1].name
    assert "dask scheduler" in timings[2].name
    assert all(t.seconds > 0 and t.cpu_seconds > 0 for t in timings)
    text = sweep_bench.render(timings, ratios, 4, 100, 200.0)
    assert text.count("\n| ") == 1 + 3  # the header and one row per run
    assert "identical fronts" in text


def test_sweep_benchmark_runs_the_bundled_example_both_ways_with_equal_fronts(tmp_path) -> None:
    """The example's path through the benchmark, on a spec of the bundled example's shape (its
    scenario file, a generated scenario, a grid, dry runs) cut to 4 cells: the bundled one's
    24 cells of 50 dry runs each cost CI over a minute and test nothing more."""
    example = sweep_bench.EXAMPLE_SPEC.read_text("utf-8")
    scenario = (sweep_bench.EXAMPLE_SPEC.parent / "example" / "scenario.toml").as_posix()
    assert 'file = "example/scenario.toml"' in example and "runs = 50" in example
    spec = tmp_path / "small-example.toml"
    spec.write_text(
        example.replace('file = "example/scenario.toml"', f'file = "{scenario}"')
        .replace("count = 3", "count = 1")
        .replace("delta = [0.001, 0.00105, 0.0011]", "delta = [0.001]")
        .replace("runs = 50", "runs = 5"),
        "utf-8",
    )
    timings, fronts = sweep_bench.run_example(tmp_path, workers=1, spec_path=spec)
    assert [t.cells for t in timings] == [4, 4] and len(fronts) == 4
    assert timings[1].start_stop > 0 and all(t.cpu_seconds > 0 for t in timings)
    text = sweep_bench.render_example(timings, spec)
    assert text.count("\n| ") == 1 + 2 and "small-example.toml" in text
