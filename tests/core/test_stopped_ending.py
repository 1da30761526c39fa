"""A search stopped by its budget ends in bounded time: past the time limit (plus a grace) the
open partial routes are no longer examined for whether a found route covers them. Kept open
unexamined, they may only weaken what the result claims, never make it wrong."""

from __future__ import annotations

from gcs_planner.core import bnb
from gcs_planner.core.bnb import Options, bnb_front
from gcs_planner.core.budget import Budget
from gcs_planner.scenario.generate import DATASET1
from gcs_planner.scenario.readers import load_scenario


def test_open_routes_left_unexamined_only_weaken_the_claims(dataset_paths) -> None:
    scenario = load_scenario(dataset_paths[1], DATASET1.to_dict())
    full = bnb_front(scenario, probability=True, max_labels=10**6)
    assert full.optimal
    limit = max(1, full.labels // 5)

    def stopped(options: Options | None = None) -> bnb.BnbResult:
        # A time limit nobody reaches gives the search a deadline; the labels stop it.
        budget = Budget(limit, 10_000.0)
        return bnb_front(scenario, probability=True, budget=budget, options=options)

    examined = stopped()
    # The deadline long past at the ending.
    unexamined = stopped(Options(ending_grace=-1e9))
    assert not examined.optimal and not unexamined.optimal
    assert [g.points for g in unexamined.front] == [g.points for g in examined.front]
    # No partial route that was open is dropped.
    assert unexamined.open_labels >= examined.open_labels
    for f, lb, lb_examined in zip(
        unexamined.front, unexamined.lower_bounds, examined.lower_bounds, strict=True
    ):
        assert lb <= lb_examined + 1e-9
        exact = min(
            g.length
            for g in full.front
            if g.corrections <= f.corrections and g.probability >= f.probability - 1e-12
        )
        assert lb <= exact + 1e-6
    for weak, strong in zip(unexamined.proven or [], examined.proven or [], strict=False):
        assert strong or not weak
