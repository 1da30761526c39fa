"""Every export of a plan, by format name, each file written atomically.

``write_all`` is what ``gcs-planner plan --out`` calls; ``export`` is ``gcs-planner export``.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.errors import InputError
from gcs_planner.mission.builder import Mission, build_mission
from gcs_planner.mission.geo_exports import csv_text, geojson_text, kml_text
from gcs_planner.mission.param_files import SETUP_FILES
from gcs_planner.mission.qgc_plan import dumps_plan
from gcs_planner.mission.waypoints import dumps_waypoints
from gcs_planner.runtime.atomic import write_atomic, write_folder_atomic

# format -> (file name in write_all, renderer of the file's content)
FORMATS: dict[str, tuple[str, Callable[[dict, Mission], str | bytes]]] = {
    "plan": ("mission.plan", lambda plan, m: dumps_plan(m)),
    "waypoints": ("mission.waypoints", lambda plan, m: dumps_waypoints(m)),
    "geojson": ("route.geojson", geojson_text),
    "kml": ("route.kml", kml_text),
    "csv": ("route.csv", csv_text),
    "png": ("route.png", lambda plan, m: _pictures().route_png(plan, m.route_index)),
    "front-png": ("front.png", lambda plan, m: _pictures().front_png(plan)),
    "error-budget-png": (
        "error_budget.png",
        lambda plan, m: _pictures().error_budget_png(plan, m.route_index),
    ),
}


def _pictures() -> ModuleType:
    # matplotlib takes most of a second to import: only the pictures pay for it.
    from gcs_planner.mission import pictures

    return pictures


def render(plan: dict, fmt: str, mission: Mission) -> str | bytes:
    """The content of one export of ``plan`` (``mission`` built from it)."""
    return FORMATS[fmt][1](plan, mission)


def export(
    plan: dict, fmt: str, out: str | os.PathLike[str], **mission_options: Any
) -> tuple[Path, Mission]:
    """Write one format to ``out``; returns the path and the mission it was built from."""
    if fmt not in FORMATS:
        raise InputError(f"unknown format {fmt!r} (one of {', '.join(FORMATS)})", field="--format")
    mission = build_mission(plan, **mission_options)
    return write_atomic(out, render(plan, fmt, mission)), mission


# The files `write_all` writes, with what its caller may add (plan.json): an existing output
# folder holding only these is an earlier run's, which `plan --out` may replace.
ALL_FILES = (*(name for name, _ in FORMATS.values()), "plan.json", *SETUP_FILES)


def render_all(plan: dict, **mission_options: Any) -> list[tuple[str, str | bytes]]:
    """(file name, content) of every export of ``plan``; raises before anything is written."""
    mission = build_mission(plan, **mission_options)
    return [
        (name, fn(plan, mission))
        for fmt, (name, fn) in FORMATS.items()
        # PX4 missions have no .waypoints (mission.waypoints explains why): .plan is theirs.
        if fmt != "waypoints" or keeps_home_item(mission.firmware)
    ]


def write_all(
    plan: dict,
    out_dir: str | os.PathLike[str],
    extra: tuple[tuple[str, str | bytes], ...] = (),
    **mission_options: Any,
) -> list[Path]:
    """Write mission.plan, mission.waypoints (ArduPilot only), route.geojson, route.kml,
    route.csv, route.png, front.png and error_budget.png (and ``extra`` files) as the folder
    ``out_dir``, all or
    nothing: rendered first, then written into a temporary folder beside it that replaces it
    (see ``atomic.write_folder_atomic``). An interruption leaves the previous folder."""
    contents = render_all(plan, **mission_options) + list(extra)
    return write_folder_atomic(out_dir, contents)
