"""``Options`` say how the branch and bound runs, never what it finds. Its Python parts are the
reference the compiled ones are held to (``test_probe_kernel``, ``test_search_kernel``,
``test_airplane_kernel`` compare the two under Options): each switch must keep its part in
Python, or those tests would compare a compiled part with itself."""

from __future__ import annotations

import collections
import dataclasses

from support.enumeration import assert_same_front, front_of, probed_front
from support.scenarios import probed_scenario

from gcs_planner.core import probe_kernel
from gcs_planner.core.bnb import Options, bnb_front
from gcs_planner.core.bnb import search as bnb_search
from gcs_planner.geometry.legs import AirplaneLegs


def _counting(monkeypatch) -> collections.Counter:
    """Counts the calls of the compiled probes, the compiled search and the compiled legs."""
    calls: collections.Counter[str] = collections.Counter()
    probe = probe_kernel.CompiledProbes.__call__
    search = bnb_search._compiled_search
    legs = AirplaneLegs.compiled_lengths

    def probes(self, *args):
        calls["probes"] += 1
        return probe(self, *args)

    def searched(*args):
        calls["search"] += 1
        return search(*args)

    def flown(self, *args):
        calls["legs"] += 1
        return legs(self, *args)

    monkeypatch.setattr(probe_kernel.CompiledProbes, "__call__", probes)
    monkeypatch.setattr(bnb_search, "_compiled_search", searched)
    monkeypatch.setattr(AirplaneLegs, "compiled_lengths", flown)
    return calls


def test_python_options_keep_each_part_in_python(monkeypatch) -> None:
    calls = _counting(monkeypatch)
    # Every part from the first label, so that these small searches use each.
    compiled = Options(probe_from=0, trial=0, compiled_legs_from=-1)
    python = dataclasses.replace(
        compiled, compiled_probes=False, compiled_search=False, compiled_legs=False
    )
    for options in (compiled, python):
        calls.clear()
        probe_labels = 0
        for seed in range(4):
            scenario = probed_scenario(seed, "airplane")
            result = bnb_front(scenario, probability=True, max_labels=10**6, options=options)
            assert result.optimal
            assert_same_front(front_of(result, True), probed_front(seed, "airplane", True), seed)
            probe_labels += result.probe_labels
        assert probe_labels > 0
        if options is compiled:
            assert min(calls["probes"], calls["search"], calls["legs"]) > 0, calls
        else:
            assert not calls, calls


def test_searches_that_never_probe_find_the_same_fronts() -> None:
    never = Options(probe_from=10**9)
    for seed in range(4):
        scenario = probed_scenario(seed, "airplane")
        result = bnb_front(scenario, probability=True, max_labels=10**6, options=never)
        assert result.optimal and result.probe_labels == 0
        assert_same_front(front_of(result, True), probed_front(seed, "airplane", True), seed)
