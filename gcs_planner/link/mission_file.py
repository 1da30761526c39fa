"""The mission a user hands to ``upload``: a QGroundControl .plan, a Mission Planner .waypoints,
or a plan JSON written by ``gcs-planner plan`` (turned into items by the mission builder).

This is the one place the link reads files, so a new format is one branch here.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from gcs_planner.errors import InputError
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
    JSON's mission (default ardupilot); a .plan says its own."""
    path = Path(path)
    suffix = path.suffix.lower()
    if not path.is_file():
        raise InputError("no such file", file=str(path))
    if suffix == ".plan":
        from gcs_planner.mission.qgc_plan import read_plan

        mf = read_plan(path)
        return MissionToUpload(tuple(mf.items), mf.firmware, None)
    if suffix == ".waypoints":
        from gcs_planner.mission.waypoints import read_waypoints

        mf = read_waypoints(path, firmware or "ardupilot")
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
            plan, route_index=route_index, firmware=firmware or "ardupilot", source=str(path)
        )
        radius = mission.loiter_param[1] if mission.loiter_param else None
        return MissionToUpload(tuple(mission.items), mission.firmware, radius)
    raise InputError(
        f"unknown mission file type {path.suffix!r}: expected .plan, .waypoints or a plan .json",
        file=str(path),
    )
