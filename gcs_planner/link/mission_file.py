"""The mission a user hands to ``upload``: a QGroundControl .plan, a Mission Planner .waypoints,
or a plan JSON written by ``gcs-planner plan`` (turned into items by the mission builder).

This is the one place the link reads files, so a new format is one branch here.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from gcs_planner.aircraft.autopilot import DEFAULT_AUTOPILOT, keeps_home_item
from gcs_planner.errors import InputError
from gcs_planner.link.validate import item_problem
from gcs_planner.mission.items import MissionItem


@dataclass(frozen=True)
class MissionToUpload:
    items: tuple[MissionItem, ...]
    firmware: str | None  # what the file was written for; None when it does not say
    loiter_radius: float | None  # the plan's turning radius, when the file carries one


def load_mission_file(
    path: str | Path, *, firmware: str | None = None, route_index: int | None = None
) -> MissionToUpload:
    """Read ``path`` by its suffix. ``firmware`` numbers a .waypoints file and builds a plan
    JSON's mission (default: the default autopilot, ArduPlane); a .plan says its own."""
    mission = _load(Path(path), firmware, route_index)
    _check_items(Path(path), mission)
    return mission


def _check_items(path: Path, mission: MissionToUpload) -> None:
    """Refuse, before anything is sent, an item no vehicle can be sent or should fly, naming
    the file, the row (of a .waypoints) or the item, and the field."""
    rows: list[int] | None = None
    for item in mission.items:
        problem = item_problem(item)
        if problem is None:
            continue
        if path.suffix.lower() == ".waypoints":
            if rows is None:
                rows = _waypoints_rows(path)
            # Row 0 is home: ArduPilot's item 0, before PX4's first item.
            index = item.seq if keeps_home_item(mission.firmware) else item.seq + 1
            if index < len(rows):
                raise InputError(problem.reason, file=str(path), row=rows[index],
                                 field=problem.field)  # fmt: skip
        raise InputError(
            f"mission item {item.seq}: {problem.reason}", file=str(path), field=problem.field
        )


def _waypoints_rows(path: Path) -> list[int]:
    """The line number of each data row of a .waypoints file, as its reader counts them."""
    lines = path.read_text(encoding="utf-8").splitlines()
    return [
        n for n, line in enumerate(lines[1:], start=2) if line.strip() and not line.startswith("#")
    ]


def _load(path: Path, firmware: str | None, route_index: int | None) -> MissionToUpload:
    suffix = path.suffix.lower()
    if not path.is_file():
        raise InputError("no such file", file=str(path))
    if suffix == ".plan":
        from gcs_planner.mission.qgc_plan import read_plan

        mf = read_plan(path)
        return MissionToUpload(tuple(mf.items), mf.firmware, None)
    if suffix == ".waypoints":
        from gcs_planner.mission.waypoints import read_waypoints

        mf = read_waypoints(path, firmware or DEFAULT_AUTOPILOT)
        return MissionToUpload(tuple(mf.items), mf.firmware, None)
    if suffix == ".json":
        from gcs_planner.mission.builder import build_mission

        try:
            plan = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError) as exc:
            raise InputError(f"cannot read: {exc}", file=str(path)) from exc
        except json.JSONDecodeError as exc:
            raise InputError(f"not JSON: {exc.msg}", file=str(path), row=exc.lineno) from exc
        mission = build_mission(
            plan, route_index=route_index, firmware=firmware or DEFAULT_AUTOPILOT, source=str(path)
        )
        radius = mission.loiter_param[1] if mission.loiter_param else None
        return MissionToUpload(tuple(mission.items), mission.firmware, radius)
    raise InputError(
        f"unknown mission file type {path.suffix!r}: expected .plan, .waypoints or a plan .json",
        file=str(path),
    )
