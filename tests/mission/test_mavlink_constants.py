"""The MAV_CMD, MAV_FRAME and MAV_MISSION_TYPE numbers the project states once (mission/items.py)
are MAVLink's: held against pymavlink's common dialect, by name."""

from __future__ import annotations

import pytest

from gcs_planner.link.connection import mavlink
from gcs_planner.mission import items

NAMED = sorted(
    name
    for name in vars(items)
    if name.startswith(("MAV_CMD_", "MAV_FRAME_", "MAV_MISSION_TYPE_"))
    and isinstance(getattr(items, name), int)
)


def test_every_family_is_stated() -> None:
    families = {name.split("_")[1] for name in NAMED}
    assert families == {"CMD", "FRAME", "MISSION"}, NAMED
    assert len(NAMED) >= 15


@pytest.mark.parametrize("name", NAMED)
def test_the_number_is_the_dialect_s(name: str) -> None:
    assert getattr(items, name) == getattr(mavlink, name), name


def test_the_sets_are_made_of_the_named_commands_and_frames() -> None:
    def names(enum: str, values: frozenset[int]) -> set[str]:
        return {mavlink.enums[enum][v].name for v in values}

    assert names("MAV_CMD", items.POSITION_COMMANDS) == {
        "MAV_CMD_NAV_WAYPOINT", "MAV_CMD_NAV_LOITER_UNLIM", "MAV_CMD_NAV_LOITER_TURNS",
        "MAV_CMD_NAV_LOITER_TIME", "MAV_CMD_NAV_LAND", "MAV_CMD_NAV_TAKEOFF",
        "MAV_CMD_NAV_LOITER_TO_ALT",
    }  # fmt: skip
    assert names("MAV_CMD", items.HELIX_COMMANDS) == {
        "MAV_CMD_NAV_LOITER_TURNS", "MAV_CMD_NAV_LOITER_TO_ALT"
    }  # fmt: skip
    amsl = {"MAV_FRAME_GLOBAL", "MAV_FRAME_GLOBAL_INT"}
    assert names("MAV_FRAME", items.GLOBAL_AMSL_FRAMES) == amsl
    assert names("MAV_FRAME", items.GLOBAL_RELATIVE_FRAMES) == {
        "MAV_FRAME_GLOBAL_RELATIVE_ALT", "MAV_FRAME_GLOBAL_RELATIVE_ALT_INT"
    }  # fmt: skip
    assert items.MISSION_FRAMES - items.GLOBAL_FRAMES == {mavlink.MAV_FRAME_MISSION}
