"""The compiled probes (``core.probe_kernel``) against the Python ones they replace: the same
answers probe by probe, so the same searches — fronts, bounds, labels and probe labels equal —
on the scenarios where probes prune (``test_probes``), two and three objectives, every leg
model with turns (floors with critical points among them: walks that revisit them), and sparse
maps with the contest's limits.
``test_probes`` holds the compiled probes' fronts to enumeration."""

from __future__ import annotations

import collections

import numpy as np
import pytest
from numba import njit
from support.scenarios import probed_scenario, sparse_scenario

from gcs_planner.core import bnb, cover_kernel, dominance_kernel, failure_bounds, probe_kernel
from gcs_planner.core.bnb import Options, dominance, incumbents
from gcs_planner.core.kernel_records import NO_FAILURES
from gcs_planner.core.reach import build_reach_graph
from gcs_planner.scenario.generate import DATASET2
from gcs_planner.scenario.readers import load_scenario


def _run(scenario, probability: bool, compiled: bool, per_arc: float = 0.0) -> bnb.BnbResult:
    """Probes from the first label, with the failure bounds made once the probes have spent
    ``per_arc`` labels per arc of the reach graph."""
    options = Options(probe_from=0, failure_bounds_per_arc=per_arc, compiled_probes=compiled)
    return bnb.bnb_front(scenario, probability=probability, max_labels=10**6, options=options)


def _same_search(a: bnb.BnbResult, b: bnb.BnbResult, case) -> None:
    assert a.front == b.front, case  # Found: length, corrections, probability, points
    assert a.lower_bounds == b.lower_bounds, case
    assert (a.labels, a.probe_labels) == (b.labels, b.probe_labels), case
    assert (a.optimal, a.proven, a.open_labels) == (b.optimal, b.proven, b.open_labels), case


@pytest.fixture
def asked(monkeypatch) -> collections.Counter:
    """Counting what the compiled probes answered and the critical points of the probers."""
    seen: collections.Counter[str] = collections.Counter()
    call = probe_kernel.CompiledProbes.__call__

    def counted(self, inc, L, node, k, states, arc, path, to_go, max_labels):
        covered, labels, escape = call(self, inc, L, node, k, states, arc, path, to_go, max_labels)
        seen["covered" if covered else "open"] += 1
        seen["by nogoods"] += covered and labels == 0
        seen["escaped"] += bool(escape)
        seen["with critical points"] += int((self.crit_bit >= 0).any())
        seen["several states"] += len(states) > 1
        return covered, labels, escape

    monkeypatch.setattr(probe_kernel.CompiledProbes, "__call__", counted)
    return seen


def test_compiled_probes_search_as_the_python_ones(asked) -> None:
    """Half the searches with the failure bounds from the first probe, half making them once
    the probes have spent a label per arc (mid-search: both probes must switch together)."""
    for legs in ("airplane", "airplane, climb limits", "cs3d"):
        for seed in range(12):
            scenario = probed_scenario(seed, legs)
            per_arc = 0.0 if seed % 2 else 1.0
            for probability in (True, False) if seed < 4 else (True,):
                compiled = _run(scenario, probability, True, per_arc)
                python = _run(scenario, probability, False, per_arc)
                _same_search(compiled, python, (legs, seed, probability))
    assert asked["covered"] >= 30 and asked["by nogoods"] >= 10, asked
    assert asked["escaped"] >= 100 and asked["several states"] >= 80, asked
    assert asked["with critical points"] >= 20, asked


def test_compiled_probes_on_sparse_maps_with_contest_limits(asked) -> None:
    for seed in range(40):
        scenario = sparse_scenario(seed)
        if scenario.params.turn_radius == 0.0:
            continue  # straight legs: no probes
        compiled = _run(scenario, True, True)
        python = _run(scenario, True, False)
        _same_search(compiled, python, seed)
    assert asked["covered"] >= 35 and asked["open"] >= 10, asked
    assert asked["by nogoods"] >= 15 and asked["several states"] >= 20, asked


def test_the_kernel_shares_the_models_constants() -> None:
    assert cover_kernel.MASS_SLACK == failure_bounds._MASS_SLACK
    assert dominance_kernel.MAX_UNIONS == dominance.MAX_UNIONS


# The kernels' inner functions have no wrapper for Python callers
# (``gcs_planner.runtime.jit.inner``):
# the tests call each through a compiled function of their own.
@njit
def stochastically_dominates(*args):  # noqa: ANN002, ANN201
    return dominance_kernel.stochastically_dominates(*args)


@njit
def failure_rows(*args):  # noqa: ANN002, ANN201
    return cover_kernel.failure_rows(*args)


@njit
def best_rows(*args):  # noqa: ANN002, ANN201
    return cover_kernel.best_rows(*args)


@njit
def level_tables(*args):  # noqa: ANN002, ANN201
    return cover_kernel.level_tables(*args)


@njit
def covers_by_level(*args):  # noqa: ANN002, ANN201
    return cover_kernel.covers_by_level(*args)


def _pool(states: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return (
        np.array([s[0] for s in states], float),
        np.array([s[1] for s in states], float),
        np.array(list(states.values()), float),
    )


def test_compiled_dominance_between_distributions_answers_as_the_python_one() -> None:
    """Hall's condition on random distributions of 1 to 12 states on a coarse grid (ties and
    nested "below" sets are common), shifted or not; enough of both answers, and supports
    whose unions exceed MAX_UNIONS."""
    rng = np.random.default_rng(7)
    answers: collections.Counter[bool] = collections.Counter()
    for _ in range(3000):
        d1 = {
            (float(rng.integers(0, 6)), float(rng.integers(0, 6))): float(rng.uniform(0.05, 1))
            for _ in range(int(rng.integers(1, 13)))
        }
        d2 = {
            (float(rng.integers(0, 8)), float(rng.integers(0, 8))): float(rng.uniform(0.05, 1))
            for _ in range(int(rng.integers(1, 13)))
        }
        shift = float(rng.choice([0.0, 0.5, 1.0]))
        want = dominance._stochastically_dominates(dominance._shifted(d1, shift), d2)
        got = stochastically_dominates(*_pool(d1), 0, len(d1), shift, *_pool(d2), 0, len(d2))
        assert got == want, (d1, d2, shift)
        answers[want] += 1
    assert answers[True] >= 300 and answers[False] >= 300, answers


def test_compiled_bounds_per_probability_level_equal_the_python_ones(dataset_paths) -> None:
    """``FailureBounds.bound`` (G^q at each state's own error, q the failures its mass must
    survive) against the kernel's, for random distributions and gaps on dataset 2 (where three
    forced failures bound more than two) and scenarios with half their points unreliable."""
    rng = np.random.default_rng(11)
    forced: collections.Counter[str] = collections.Counter()
    deepest = 0  # bounds where G^3 says more than G^2
    scenarios = [load_scenario(dataset_paths[2], DATASET2.to_dict())]
    scenarios += [probed_scenario(seed, "airplane") for seed in range(3)]
    for scenario in scenarios:
        fb = failure_bounds.failure_bounds(scenario, build_reach_graph(scenario))
        assert fb is not None
        record = fb.record()
        for _ in range(400):
            j = int(rng.integers(0, scenario.n))
            masses = rng.dirichlet(np.ones(int(rng.integers(1, 5)))) * rng.uniform(0.3, 1.0)
            states = {
                (float(rng.uniform(0, 8_000)), float(rng.uniform(0, 8_000))): float(m)
                for m in masses
            }
            gap = float(rng.choice([1e-3, 0.01, 0.05, 0.2, 0.5]))
            want = fb.bound(j, states, gap)
            got = failure_rows(record, j, *_pool(states), 0, len(states), gap)
            if want is None:
                assert len(got) == 0
                continue
            np.testing.assert_array_equal(got, want)
            for (v, h), w in states.items():
                q = fb.forced(w, gap)
                forced[str(q)] += 1
                e = h if fb.is_v[j] else v
                three, two = fb.rows(j, e, 3), fb.rows(j, e, 2)
                if q == 3 and two is not None and (three is None or (three > two).any()):
                    deepest += 1
    assert all(forced[q] >= 50 for q in ("-1", "0", "1", "2", "3")), forced
    assert deepest >= 20, deepest


def test_compiled_test_per_probability_level_answers_as_the_python_one() -> None:
    """``cover_kernel.covers_by_level`` against ``_Incumbents.covers_by_level`` with random
    found routes, ceilings and bounds to go much shorter than the corrections still allowed
    (where the kernel decides the rest at once from ``level_tables``)."""
    rng = np.random.default_rng(5)
    answers: collections.Counter[bool] = collections.Counter()
    tails = 0
    for _ in range(3000):
        kmax = int(rng.integers(3, 30))
        inc = incumbents._Incumbents(kmax)
        for _ in range(int(rng.integers(0, 8))):
            inc.add(
                bnb.Found(
                    float(rng.uniform(100, 200)), int(rng.integers(0, kmax + 1)),
                    float(rng.choice([1.0, 0.8, 0.64, 0.5, float(rng.uniform(0.1, 1))])), (0, 1),
                )
            )  # fmt: skip
        ceiling = None
        if rng.random() < 0.7:
            relaxed = [
                bnb.Found(float(rng.uniform(80, 190)), int(rng.integers(0, kmax + 1)),
                          float(rng.uniform(0.05, 1)), (0, 1))
                for _ in range(int(rng.integers(1, 8)))
            ]  # fmt: skip
            ceiling = bnb.Ceiling(relaxed, kmax)
        k = int(rng.integers(0, kmax + 1))
        to_go = np.minimum.accumulate(rng.uniform(0, 80, int(rng.integers(1, 5))))
        length, mass = float(rng.uniform(0, 120)), float(rng.uniform(0.05, 1))
        want = inc.covers_by_level(length, k, mass, lambda gap, b=to_go: b, ceiling)
        levels = np.array(inc.levels(), float)
        p = np.array([f.probability for f in inc.found], float)
        order = np.argsort(p, kind="stable").astype(np.int64)
        best = best_rows(
            np.array([f.length for f in inc.found], float),
            np.array([f.corrections for f in inc.found], np.int64), order, kmax,
        )  # fmt: skip
        has_ceil = ceiling is not None
        ceil_rows = np.empty((0, kmax + 1))
        if has_ceil:
            above = [*levels, -np.inf]
            ceil_rows = np.vstack([ceiling.least_above(float(lo)) for lo in above])
        tables = level_tables(levels, np.sort(p), best, has_ceil, ceil_rows, kmax)
        one = np.zeros(1)
        got = covers_by_level(
            length, k, mass, to_go, kmax, levels, *tables, has_ceil, ceil_rows, NO_FAILURES, 0,
            one, one, np.ones(1), 0, 1,
        )  # fmt: skip
        assert got == want
        answers[want] += 1
        tails += len(to_go) < kmax - k + 1
    assert answers[True] >= 300 and answers[False] >= 300 and tails >= 1000, (answers, tails)
