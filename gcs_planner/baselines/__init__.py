"""Independent comparators for the exact search: brute force, a MILP, and the paper's NSGA-II.

They share nothing with ``gcs_planner.core.search`` on purpose — a check that reuses the code it
checks proves nothing. They use only the scenario and ``evaluate_route`` (the one statement of the
error model along a fixed route), with straight legs and two objectives: total length and number
of corrections.

A front is a list of ``(length, corrections, route)`` sorted by increasing corrections (hence
decreasing length); ``route`` holds point indices, A first and B last.
"""

from __future__ import annotations

Front = list[tuple[float, int, tuple[int, ...]]]

__all__ = ["Front"]
