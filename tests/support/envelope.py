"""A contest workbook read as `gcs-planner plan` reads it, with the envelope derived for an
autopilot's shipped defaults in a design wind."""

from __future__ import annotations

from pathlib import Path

from gcs_planner.aircraft.derive import derive_envelope
from gcs_planner.cli import build_parser
from gcs_planner.cli.common import load_scenario_from_args
from gcs_planner.scenario.model import Scenario

# The contest's Table 2 limits of each dataset, as flags (delta apart).
TABLE2 = {
    1: ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30"],
    2: ["--alpha1", "20", "--alpha2", "10", "--beta1", "15", "--beta2", "20", "--theta", "20"],
}


def scenario_in_wind(
    path: Path, dataset: int, firmware: str, wind: str, per_leg: bool = False
) -> Scenario:
    """The workbook at ``path`` with dataset ``dataset``'s limits, delta 0.001, and the envelope
    ``firmware``'s defaults give in the design wind ``wind`` (per leg when ``per_leg``)."""
    argv = ["plan", str(path), *TABLE2[dataset], "--delta", "0.001", "--firmware", firmware,
            "--wind", str(wind), *(["--per-leg-envelope"] if per_leg else [])]  # fmt: skip
    args = build_parser(argv).parse_args(argv)
    return derive_envelope(args, load_scenario_from_args(args), wind_text=args.wind)
