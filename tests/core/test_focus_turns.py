"""The branch and bound searched over the ellipsoid that a route with the fewest corrections
bounds (``core.focus``, large maps) against the same search over every point."""

from __future__ import annotations

import pytest
from support.scenarios import sparse_scenario

from gcs_planner.core import focus
from gcs_planner.core.planner import plan
from gcs_planner.core.seeding import certain_front
from gcs_planner.errors import InfeasibleError

TWO = ("length", "corrections")
THREE = ("length", "corrections", "probability")


def _front(result):
    return [(round(r.length, 6), r.corrections, round(r.probability, 12)) for r in result.routes]


@pytest.mark.parametrize("objectives", [TWO, THREE])
def test_a_focused_front_is_the_front_over_every_point(monkeypatch, objectives) -> None:
    focused = 0
    for seed in range(24):
        scenario = sparse_scenario(seed)
        monkeypatch.setattr(focus, "FOCUS_FROM", 0)
        try:
            got = plan(scenario, objectives=objectives, max_labels=None)
        except InfeasibleError:
            got = None
        monkeypatch.setattr(focus, "FOCUS_FROM", 10**9)
        try:
            want = plan(scenario, objectives=objectives, max_labels=None)
        except InfeasibleError:
            assert got is None, seed
            continue
        assert want.stats["points"] == scenario.n
        assert got is not None and got.optimal and want.optimal, seed
        assert _front(got) == _front(want), seed
        if got.stats["points"] < scenario.n:
            focused += 1
            assert "ellipsoid" in got.statement
    assert focused >= 8


def test_the_bound_holds_every_front_route() -> None:
    """``front_bound`` against the exact front over every point: no front route is longer."""
    bounded = 0
    for seed in range(24):
        scenario = sparse_scenario(seed)
        certain = certain_front(scenario)
        for objectives in (TWO, THREE):
            probability = len(objectives) == 3
            bound = focus.front_bound(scenario, certain, certain.seeds, probability)
            if bound is None:
                continue
            # (A bound comes from a feasible route: the plan has one, or raises and fails.)
            exact = plan(scenario, objectives=objectives, max_labels=None)
            assert max(r.length for r in exact.routes) <= bound * (1 + 1e-9), seed
            bounded += 1
    assert bounded >= 10
