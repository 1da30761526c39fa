"""The benchmark's scenarios, named by a short spec so that a child process can rebuild them.

``dataset1`` / ``dataset2``: the contest workbooks with the paper's parameters (Table 2);
``random-N``: ``random_scenario(N, seed=RANDOM_SEED, params=DATASET1)``, the contest's 100 km box;
``small-N``: the same in a 40 × 20 × 2 km box, dense enough for a few points to have routes (the
smoke run's scenario); ``corridor-N``: the same in a 300 × 20 × 2 km corridor with straight legs
(long routes of 24 and more corrections, fronts of many routes).
"""

from __future__ import annotations

from pathlib import Path

from gcs_planner.scenario.generate import DATASET1, DATASET2, random_scenario
from gcs_planner.scenario.model import Parameters, Scenario
from gcs_planner.scenario.readers import load_scenario

# The workbooks stay in ../shared beside the repository (never copied into it).
DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "gmcm2019f"
DATASETS: dict[str, Parameters] = {"dataset1": DATASET1, "dataset2": DATASET2}
RANDOM_SEED = 1
SMALL_BOX = (40_000.0, 20_000.0, 2_000.0)
CORRIDOR_BOX = (300_000.0, 20_000.0, 2_000.0)


def valid_spec(spec: str) -> bool:
    """Whether ``spec`` names a scenario :func:`load_case` can build."""
    if spec in DATASETS:
        return True
    prefix, _, n = spec.partition("-")
    return prefix in ("random", "small", "corridor") and n.isdigit()


def load_case(spec: str, turn_radius: float | None = None) -> Scenario:
    """The scenario named ``spec``; ``turn_radius`` overrides the parameters' radius."""
    if spec in DATASETS:
        params = DATASETS[spec]
        path = DATA / f"{spec}.xlsx"
        if not path.exists():
            raise FileNotFoundError(f"{path} not found: ../shared must be beside the repository")
        scenario = load_scenario(path, params.to_dict())
    elif spec.startswith("random-"):
        scenario = random_scenario(int(spec.removeprefix("random-")), RANDOM_SEED, params=DATASET1)
    elif spec.startswith("small-"):
        n = int(spec.removeprefix("small-"))
        scenario = random_scenario(n, RANDOM_SEED, params=DATASET1, box=SMALL_BOX)
    elif spec.startswith("corridor-"):
        n = int(spec.removeprefix("corridor-"))
        scenario = random_scenario(n, RANDOM_SEED, params=DATASET1, box=CORRIDOR_BOX)
        scenario = scenario.with_params(turn_radius=0.0)
    else:
        raise ValueError(f"unknown scenario {spec!r}")
    if turn_radius is not None:
        scenario = scenario.with_params(turn_radius=turn_radius)
    return scenario
