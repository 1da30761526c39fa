"""The compiled searches over walks (``core.search_kernel``: the floors and the guide of the
branch and bound with turns) against the Python ones: the same searches, whole plans compared
field by field, also when a label budget or the time limit stops them; and fronts still those
of enumeration. (Importing the kernel here means that, from now on in this process, such
searches run compiled from their first label, without the Python trial.)"""

from __future__ import annotations

import collections

from support.compiled_search import assert_same_search, searched_both_ways
from support.enumeration import assert_same_front, front_of, probed_front
from support.scenarios import probed_scenario

from gcs_planner.core import search_kernel
from gcs_planner.core.bnb import search as bnb_search
from gcs_planner.core.budget import Budget

LEGS = ("airplane", "airplane, climb limits", "cs3d")


def test_compiled_searches_equal_the_python_ones_and_enumeration(monkeypatch) -> None:
    modes: collections.Counter[int] = collections.Counter()
    legs_mode = bnb_search._legs_mode

    def counted(ctx, critical):
        mode = legs_mode(ctx, critical)
        modes[mode] += 1
        return mode

    monkeypatch.setattr(bnb_search, "_legs_mode", counted)
    for legs in LEGS:
        for seed in range(10):
            scenario = probed_scenario(seed, legs)
            for probability in (True, False) if seed < 4 else (True,):
                compiled, python = searched_both_ways(scenario, probability)
                assert_same_search(compiled, python, (legs, seed, probability))
                want = probed_front(seed, legs, probability)
                assert_same_front(front_of(compiled, probability), want, (legs, seed))
    # Every kind of legs ran compiled: heading-free, the pair relaxation's, airplane, cs3d.
    assert modes[0] >= 20 and modes[1] >= 10 and modes[2] >= 10 and modes[3] >= 5, modes


def test_compiled_searches_stop_where_the_python_ones_do(monkeypatch) -> None:
    """Label budgets that stop the floors or the guide midway, and a time limit of 0."""
    stopped = collections.Counter()
    compiled_search = bnb_search._compiled_search

    def counted(*args):
        result = compiled_search(*args)
        stopped["compiled, stopped" if not result.exhausted else "compiled, exhausted"] += 1
        return result

    monkeypatch.setattr(bnb_search, "_compiled_search", counted)
    for legs in LEGS:
        for seed in range(4):
            scenario = probed_scenario(seed, legs)
            for limit in (5, 40, 150):
                compiled, python = searched_both_ways(scenario, True, max_labels=limit)
                assert_same_search(compiled, python, (legs, seed, limit))
            compiled, python = searched_both_ways(scenario, True, max_labels=None, time_limit=0)
            assert_same_search(compiled, python, (legs, seed, "time"))
            assert not compiled.exhausted and compiled.labels == 0
    assert stopped["compiled, stopped"] >= 20 and stopped["compiled, exhausted"] >= 5, stopped


def test_the_kernel_reports_progress_and_the_time_limit(monkeypatch) -> None:
    """``tick`` asks the budget of the search running: progress when due, the time limit."""
    seen = []
    budget = Budget(None, time_limit=1e6, progress=seen.append, every=0.0)
    search_kernel._BUDGETS.append(budget)
    try:
        assert search_kernel.tick(64, 10, 2, 1234.5) is False
    finally:
        search_kernel._BUDGETS.pop()
    assert [(p.labels, p.open_routes, p.routes_found) for p in seen] == [(64, 10, 2)]
    late = Budget(None, time_limit=0)
    search_kernel._BUDGETS.append(late)
    try:
        assert search_kernel.tick(0, 0, 0, 0.0) is True
    finally:
        search_kernel._BUDGETS.pop()
