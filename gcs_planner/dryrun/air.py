"""The vertical turbulence a dry run flies: ``--turbulence``, else the scenario TOML's
``[environment] turbulence``, else none (sim/turbulence.py: the Dryden vertical component of
MIL-F-8785C, a sigma_w in m/s or a level of the standard)."""

from __future__ import annotations

from pathlib import Path

from gcs_planner.errors import InputError
from gcs_planner.scenario.toml_reader import read_scenario_toml
from gcs_planner.sim.turbulence import Turbulence, parse_turbulence

FLAG = "--turbulence"


def flown_turbulence(text: str | None, scenario: str | Path | None) -> Turbulence | None:
    """The turbulence of the flag's ``text`` (SIGMA_W or light, moderate, severe), else of the
    scenario file's ``[environment] turbulence``; None when neither gives one. A bad value is an
    InputError naming the flag, or the file and its key."""
    if text is not None:
        try:
            return _present(parse_turbulence(text))
        except ValueError as exc:
            raise InputError(str(exc), field=FLAG) from None
    if scenario is None or Path(scenario).suffix.lower() != ".toml":
        return None
    spec = read_scenario_toml(Path(scenario))
    if "turbulence" not in spec.environment:
        return None
    value, _ = spec.environment["turbulence"]
    return _present(parse_turbulence(str(value)))


def _present(turbulence: Turbulence) -> Turbulence | None:
    return turbulence if turbulence.present else None


DESIGN_FLAG = "--design-turbulence"


def design_turbulence(text: str | None, flown: Turbulence | None) -> Turbulence | None:
    """The turbulence the dry run's plan is made for: ``--design-turbulence`` (0: none), else
    the turbulence flown, as ``--design-wind`` defaults to ``--wind``."""
    if text is None:
        return flown
    try:
        return _present(parse_turbulence(text))
    except ValueError as exc:
        raise InputError(str(exc), field=DESIGN_FLAG) from None
