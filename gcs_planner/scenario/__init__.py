"""Scenarios: points, kinds, parameters, and readers for the real file formats."""

from gcs_planner.scenario.model import PARAMETER_NAMES, Kind, Origin, Parameters, Scenario

__all__ = ["PARAMETER_NAMES", "Kind", "Origin", "Parameters", "Scenario"]
