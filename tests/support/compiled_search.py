"""The compiled searches over walks (``core.search_kernel``) held against the Python ones: both
run on one scenario, compared field by field, and the legs mode each search ran with.

Importing this module imports the kernel: from then on in the process such searches run
compiled from their first label, without the Python trial (``bnb.search``), which is what the
tests using it check."""

from __future__ import annotations

from gcs_planner.core import bnb, search_kernel  # noqa: F401 - loaded: searches run compiled
from gcs_planner.core.bnb import Options
from gcs_planner.core.budget import Budget
from gcs_planner.scenario.model import Scenario

from .enumeration import assert_same_front, dfs_front, front_of


def searched_both_ways(scenario: Scenario, probability: bool, **budget: object) -> tuple:
    """(the compiled search's result, the Python one's), each under its own ``Budget(**budget)``
    when a budget is given."""
    results = []
    for compiled in (True, False):
        b = Budget(**budget) if budget else None
        options = Options(compiled_search=compiled)
        results.append(
            bnb.bnb_front(
                scenario, probability=probability, max_labels=10**6, budget=b, options=options
            )
        )
    return tuple(results)


def assert_same_search(a: bnb.BnbResult, b: bnb.BnbResult, case: object) -> None:
    """The same routes, labels, proofs and lower bounds (lengths within 1e-6 m)."""
    assert [f.points for f in a.front] == [f.points for f in b.front], case
    assert [(f.corrections, f.probability) for f in a.front] == [
        (f.corrections, f.probability) for f in b.front
    ], case
    for f, g in zip(a.front, b.front):
        assert abs(f.length - g.length) <= 1e-6, case
    assert (a.labels, a.probe_labels, a.open_labels) == (b.labels, b.probe_labels, b.open_labels)
    assert (a.optimal, a.proven, a.exhausted) == (b.optimal, b.proven, b.exhausted), case
    for x, y in zip(a.lower_bounds, b.lower_bounds):
        assert abs(x - y) <= 1e-6, case


def assert_compiled_flies_as_python(scenario: Scenario, case: object) -> None:
    """The compiled search equals the Python one (three objectives), label for label, and its
    front equals depth-first enumeration's."""
    compiled, python = searched_both_ways(scenario, True)
    assert_same_search(compiled, python, case)
    assert_same_front(front_of(compiled, True), dfs_front(scenario, True), case)


def legs_modes(monkeypatch) -> list:  # noqa: ANN001 - pytest's monkeypatch
    """The legs mode (search_kernel.LEGS_*, or None: the Python search) of every search the
    branch and bound runs from now on, appended as they run: so a test can show the compiled
    search really flew its legs."""
    from gcs_planner.core.bnb import search as bnb_search

    modes: list = []
    legs_mode = bnb_search._legs_mode

    def counted(ctx, critical):  # noqa: ANN001, ANN202
        modes.append(legs_mode(ctx, critical))
        return modes[-1]

    monkeypatch.setattr(bnb_search, "_legs_mode", counted)
    return modes
