"""What ``plan --policy --out`` writes for switching on board: ``onboard.plan`` (and
``onboard.waypoints`` for ArduPilot), the policy's missions as one (mission/onboard_mission.py),
and ``policy.lua``, the applet that switches them on an autopilot that runs Lua applets
(mission/onboard_applet.py); and the ``onboard`` section of policy.json that names them."""

from __future__ import annotations

from typing import Any

from gcs_planner.aircraft.autopilot import autopilot_for
from gcs_planner.mission.onboard_applet import (
    APPLET_FILE,
    PARAM_TABLE_KEY,
    REPORT_PARAM,
    TICK_MS,
    applet_text,
    point_codes,
)
from gcs_planner.mission.onboard_mission import ONBOARD_PLAN, ONBOARD_WAYPOINTS, onboard_mission
from gcs_planner.mission.policy_missions import PolicyMissions
from gcs_planner.mission.qgc_plan import dumps_plan
from gcs_planner.mission.waypoints import dumps_waypoints
from gcs_planner.scenario.model import Scenario

ONBOARD_FILES = (ONBOARD_PLAN, ONBOARD_WAYPOINTS, APPLET_FILE)


def render_onboard(
    scenario: Scenario, missions: PolicyMissions
) -> tuple[list[tuple[str, str]], dict[str, Any]]:
    """((file name, text) of each onboard file, policy.json's ``onboard`` section)."""
    onboard = onboard_mission(missions)
    mission = onboard.mission
    ap = autopilot_for(mission.firmware)
    files = [(ONBOARD_PLAN, dumps_plan(mission))]
    section: dict[str, Any] = {"plan": ONBOARD_PLAN, "items": len(mission.items)}
    if ap.home_at_seq0:  # .waypoints carries home as row 0 (mission/waypoints.py)
        files.append((ONBOARD_WAYPOINTS, dumps_waypoints(mission)))
        section["waypoints"] = ONBOARD_WAYPOINTS
    if ap.runs_lua_applets:
        files.append((APPLET_FILE, applet_text(onboard, point_codes(scenario.ids), scenario.name)))
        section.update(
            applet=APPLET_FILE,
            report_parameter=REPORT_PARAM,
            parameter_table_key=PARAM_TABLE_KEY,
            tick_ms=TICK_MS,
        )
    section["segments"] = [
        {"mission": name, "first": seg.first, "from_item": seg.base, "items": seg.count}
        for name, seg in onboard.segments.items()
        if seg.mission == name
    ]
    section["switches"] = [
        {
            "mission": s.mission,
            "point": s.point,
            "report_code": point_codes(scenario.ids)[s.point],
            "item": s.item,
            "to_mission": s.to_mission,
            "resume": s.resume,
            "late": s.late,
            "jump": s.jump,
        }
        for s in onboard.switches
    ]
    return files, section
