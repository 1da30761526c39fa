"""The sweep benchmark's smoke run: serial loop, local cluster and a separately started
`dask scheduler` / `dask worker` give the same fronts (run_benchmark raises if they differ)."""

from __future__ import annotations

from benchmarks import sweep as sweep_bench


def test_sweep_benchmark_runs_all_three_ways_with_equal_fronts() -> None:
    timings, ratios = sweep_bench.run_benchmark(4, corrections=40, workers=2, rounds=2)
    assert [t.cells for t in timings] == [4, 4, 4] and len(ratios) == 2
    assert "serial" in timings[0].name and "local cluster" in timings[1].name
    assert "dask scheduler" in timings[2].name
    assert all(t.seconds > 0 and t.cpu_seconds > 0 for t in timings)
    text = sweep_bench.render(timings, ratios, 4, 40, 200.0)
    assert text.count("\n| ") == 1 + 3  # the header and one row per run
    assert "identical fronts" in text


def test_sweep_benchmark_runs_the_bundled_example_both_ways_with_equal_fronts(tmp_path) -> None:
    timings, fronts = sweep_bench.run_example(tmp_path, workers=2)
    assert [t.cells for t in timings] == [24, 24] and len(fronts) == 24
    assert timings[1].start_stop > 0 and all(t.cpu_seconds > 0 for t in timings)
    text = sweep_bench.render_example(timings)
    assert text.count("\n| ") == 1 + 2 and "sweep-example.toml" in text
