"""plan(): the front is reported whole, the choice honours a least probability of arriving."""

from __future__ import annotations

import pytest

from gcs_planner.cli import main
from gcs_planner.core.choose import choose
from gcs_planner.core.planner import plan
from gcs_planner.errors import InfeasibleError
from gcs_planner.scenario.generate import random_scenario
from gcs_planner.scenario.model import Parameters

OBJECTIVES = ("length", "corrections", "probability")


def uncertain_fronts():
    """Plans of small scenarios whose front holds routes of different probabilities."""
    for seed in range(200):
        params = Parameters(25, 15, 20, 25, 30, 0.001, turn_radius=0.0, fail_residual=5.0)
        scenario = random_scenario(
            12, seed, params=params, box=(50_000, 12_000, 1_000), unreliable_fraction=0.7
        )
        try:
            result = plan(scenario, objectives=OBJECTIVES)
        except InfeasibleError:
            continue
        probs = sorted({round(r.probability, 12) for r in result.routes})
        if len(probs) >= 2:
            yield scenario, result, probs


def test_min_probability_restricts_the_choice_not_the_front() -> None:
    cases = raised = 0
    for scenario, free, probs in uncertain_fronts():
        for threshold in probs:
            for how in ("compromise", "shortest", "fewest"):
                bound = plan(scenario, objectives=OBJECTIVES, choice=how, min_probability=threshold)
                assert [r.points for r in bound.routes] == [r.points for r in free.routes]
                assert bound.route.probability >= threshold - 1e-12
                eligible = [r for r in bound.routes if r.probability >= threshold - 1e-12]
                want = choose(
                    [r.length for r in eligible],
                    [r.corrections for r in eligible],
                    [r.probability for r in eligible],
                    how,
                )
                assert bound.route.points == eligible[want].points
        above = max(probs) + (1 - max(probs)) / 2
        if max(probs) < 1:
            fallback = plan(scenario, objectives=OBJECTIVES, min_probability=above)
            assert not fallback.threshold_met
            assert fallback.route.probability == pytest.approx(max(probs), abs=1e-12)
            assert fallback.chosen == fallback.most_reliable
            raised += 1
        cases += 1
        if cases >= 15:
            break
    assert cases >= 10 and raised >= 1


def test_min_probability_flag_is_checked(capsys) -> None:
    rc = main(["plan", "missions/example/scenario.toml", "--min-probability", "1.5"])
    assert rc == 2
    assert "--min-probability" in capsys.readouterr().err
