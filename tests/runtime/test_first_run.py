"""A first plan after installing: with numba's cache empty, a plan Python proves quickly runs in
Python (nothing compiled) and gives the same plan. (`gcs-planner compile` filling the cache:
tests/runtime/test_compile_notice.py, which compiles once for both.)"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from gcs_planner.core.bnb.context import Options, first_run
from gcs_planner.core.planner import plan
from gcs_planner.library import load_scenario

TABLE2 = ["--alpha1", "20", "--alpha2", "10", "--beta1", "15", "--beta2", "20", "--theta", "20",
          "--delta", "0.001"]  # fmt: skip


def _cli(args: list[str], cache: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    env.pop("GCS_PLANNER_COMPILE", None)
    return subprocess.run(
        [sys.executable, "-m", "gcs_planner", *args], env=env, capture_output=True, text=True
    )


def _kernel_files(cache: Path) -> list[str]:
    return sorted(p.name for p in cache.rglob("*.nbi")) if cache.exists() else []


def test_the_first_run_options_follow_numbas_cache(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "empty"))
    if "gcs_planner.core.search_kernel" in sys.modules:
        # Loaded in this process already: its kernels are there, whatever the cache says.
        assert first_run(Options()) == Options()
        return
    monkeypatch.setenv("GCS_PLANNER_COMPILE", "always")
    assert first_run(Options()) == Options()
    monkeypatch.delenv("GCS_PLANNER_COMPILE")
    got = first_run(Options())
    assert got.trial == Options().uncached_trial and got.probes_after_search
    assert got.compiled_legs_from == Options().uncached_trial
    # Everything else as the defaults: the same front is searched, only in Python longer.
    assert got == Options(
        trial=got.trial, compiled_legs_from=got.compiled_legs_from, probes_after_search=True
    )


def test_a_first_plan_compiles_nothing_and_plans_the_same(tmp_path, dataset_paths) -> None:
    """Dataset 2's default plan (turns, three objectives) from an empty cache: Python proves it
    (no kernel file is written) and its plan JSON's front is the library's."""
    cache = tmp_path / "numba"
    got = _cli(["plan", str(dataset_paths[2]), *TABLE2, "--json"], cache)
    assert got.returncode == 0, got.stderr
    assert _kernel_files(cache) == []
    data = json.loads(got.stdout)
    sc = load_scenario(
        dataset_paths[2], alpha1=20, alpha2=10, beta1=15, beta2=20, theta=20, delta=0.001
    )
    want = plan(sc)
    assert [r["route"] for r in data["front"]] == [list(r.ids()) for r in want.routes]
    assert data["optimality"]["optimal"] and want.optimal
