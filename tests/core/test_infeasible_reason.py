"""An infeasible scenario says why, in every search mode: the limit, point or leg that rules
every route out, with its numbers (``core.diagnose``), through plan() and the command line."""

from __future__ import annotations

import numpy as np
import pytest
from support.paths import MISSIONS

from gcs_planner.cli import main
from gcs_planner.core.planner import plan
from gcs_planner.errors import InfeasibleError
from gcs_planner.scenario.model import Kind, Parameters, Scenario
from gcs_planner.scenario.readers import load_scenario

EXAMPLE = MISSIONS / "example" / "scenario.toml"
TWO = ("length", "corrections")
THREE = ("length", "corrections", "probability")
# (leg model, turning radius): every search mode the planner has.
MODES = [("airplane", 0.0), ("airplane", 200.0), ("cs3d", 200.0)]
# The case, its change to the scenario, max_corrections, and what the reason must name.
CASES = {
    "alpha2": ({"alpha2": 1.0}, None, ["alpha2=1 rules every route out", "reaches a V point"]),
    "theta": ({"theta": 1.0}, None, ["theta=1 rules every route out", "within theta=1"]),
    "no corrections": (
        {},
        0,
        ["--max-corrections 0 forbids corrections", "60,020 m from A", "against theta=30"],
    ),
    "radius": (
        {"turn_radius": 1e9},
        None,
        ["with turning radius 1e+09 m", "no second leg can be flown", "inside the turning"],
    ),
}


def reason(scenario: Scenario, objectives, max_corrections: int | None = None) -> str:
    with pytest.raises(InfeasibleError) as info:
        plan(scenario, objectives=objectives, max_corrections=max_corrections)
    text = str(info.value)
    assert "(exhaustive search): " in text, text
    return text


# Every case in every mode, but the radius case in straight mode: a turning radius is what that
# case sets.
CASE_MODES = [
    pytest.param(case, leg_model, radius, id=f"{case}-{name}")
    for case in CASES
    for (leg_model, radius), name in zip(MODES, ("straight", "airplane", "cs3d"))
    if not (case == "radius" and radius == 0)
]


@pytest.mark.parametrize("objectives", [TWO, THREE], ids=["two", "three"])
@pytest.mark.parametrize(("case", "leg_model", "radius"), CASE_MODES)
def test_plan_names_the_reason(case: str, leg_model: str, radius: float, objectives) -> None:
    change, max_corrections, expected = CASES[case]
    change = {"turn_radius": radius, **change}
    scenario = load_scenario(EXAMPLE, {}).with_params(**change)
    text = reason(scenario.with_vehicle(leg_model=leg_model), objectives, max_corrections)
    for part in expected:
        assert part in text, (part, text)


def test_no_correction_point_within_reach_of_a() -> None:
    scenario = load_scenario(EXAMPLE, {}).with_params(alpha1=1.0, beta1=1.0, turn_radius=0.0)
    text = reason(scenario, TWO)
    assert "its direct leg accumulates 60.02 units of error against theta=30" in text
    assert "no correction point can be reached from A" in text
    assert "the nearest V point" in text and "against alpha1=1" in text


def test_straight_leg_too_steep_for_the_climb_limit() -> None:
    """R = 0 with climb limits: the direct leg is no arc of the graph, and the reason says so
    (before the fix the search flew it and called the route optimal)."""
    xyz = np.array([[0.0, 0.0, 0.0], [10_000.0, 0.0, 3_000.0]])
    params = Parameters(
        25, 15, 20, 25, 20, 0.001, turn_radius=0.0, max_climb_angle=10, max_descent_angle=10
    )
    scenario = Scenario(
        ("0", "1"), xyz, np.array([Kind.A, Kind.B], np.uint8), np.zeros(2, bool), params
    )
    text = reason(scenario, TWO)
    assert "the direct leg A->B climbs at 16.7 deg" in text
    assert "climb limit of 10 deg" in text


@pytest.mark.parametrize(
    ("flags", "expected"),
    [
        (["--alpha2", "1"], "alpha2=1 rules every route out"),
        (["--theta", "1"], "theta=1 rules every route out"),
        (["--max-corrections", "0"], "--max-corrections 0 forbids corrections"),
        (["--turn-radius", "1e9"], "no second leg can be flown"),
    ],
    ids=["alpha2", "theta", "max-corrections", "turn-radius"],
)
def test_command_line_says_why_in_one_line(capsys, flags: list[str], expected: str) -> None:
    limits = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25"]
    limits += ["--theta", "30", "--delta", "0.001"]
    code = main(["plan", str(EXAMPLE), *limits, *flags])
    out, err = capsys.readouterr()
    assert code == 3
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gcs-planner: error: "), err
    assert expected in lines[0] and "Traceback" not in err + out
