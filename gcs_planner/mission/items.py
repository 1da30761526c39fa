"""Mission items as plain data, with MAVLink common.xml semantics (MISSION_ITEM_INT).

The files (.plan, .waypoints), the link and the mock vehicle all speak in these; none of them
knows how the route was planned. The MAV_CMD, MAV_FRAME and MAV_MISSION_TYPE numbers are
pymavlink's (its MAVLink 2 common dialect), named here once for the project.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from pymavlink.dialects.v20 import common

# MAV_FRAME
MAV_FRAME_GLOBAL = common.MAV_FRAME_GLOBAL
MAV_FRAME_MISSION = common.MAV_FRAME_MISSION
MAV_FRAME_GLOBAL_RELATIVE_ALT = common.MAV_FRAME_GLOBAL_RELATIVE_ALT
MAV_FRAME_GLOBAL_INT = common.MAV_FRAME_GLOBAL_INT
MAV_FRAME_GLOBAL_RELATIVE_ALT_INT = common.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
# Altitude above mean sea level / above home; both spellings (float degrees, _INT degE7).
GLOBAL_AMSL_FRAMES = frozenset({MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_INT})
GLOBAL_RELATIVE_FRAMES = frozenset(
    {MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_FRAME_GLOBAL_RELATIVE_ALT_INT}
)
# The global frames whose x/y the files and the link scale as latitude/longitude (terrain
# frames are not among them).
GLOBAL_FRAMES = GLOBAL_AMSL_FRAMES | GLOBAL_RELATIVE_FRAMES
# What the files we write and read can carry: the global frames and MAV_FRAME_MISSION for
# non-position items.
MISSION_FRAMES = GLOBAL_FRAMES | {MAV_FRAME_MISSION}

# MAV_CMD
MAV_CMD_NAV_WAYPOINT = common.MAV_CMD_NAV_WAYPOINT
MAV_CMD_NAV_LOITER_UNLIM = common.MAV_CMD_NAV_LOITER_UNLIM
MAV_CMD_NAV_LOITER_TURNS = common.MAV_CMD_NAV_LOITER_TURNS
MAV_CMD_NAV_LOITER_TO_ALT = common.MAV_CMD_NAV_LOITER_TO_ALT
MAV_CMD_NAV_RETURN_TO_LAUNCH = common.MAV_CMD_NAV_RETURN_TO_LAUNCH
MAV_CMD_NAV_LAND = common.MAV_CMD_NAV_LAND
MAV_CMD_DO_CHANGE_SPEED = common.MAV_CMD_DO_CHANGE_SPEED
MAV_CMD_NAV_LOITER_TIME = common.MAV_CMD_NAV_LOITER_TIME
MAV_CMD_NAV_TAKEOFF = common.MAV_CMD_NAV_TAKEOFF
# The MAV_CMD_NAV_* commands whose x/y/z are a position the vehicle flies to (waypoint, the
# loiters, land, takeoff): what the files, the link's checks and the mock vehicle treat as places.
POSITION_COMMANDS = frozenset(
    {
        MAV_CMD_NAV_WAYPOINT,
        MAV_CMD_NAV_LOITER_UNLIM,
        MAV_CMD_NAV_LOITER_TURNS,
        MAV_CMD_NAV_LOITER_TIME,
        MAV_CMD_NAV_LAND,
        MAV_CMD_NAV_TAKEOFF,
        MAV_CMD_NAV_LOITER_TO_ALT,
    }
)
# The loiters the exporter writes for the planner's helices.
HELIX_COMMANDS = frozenset({MAV_CMD_NAV_LOITER_TURNS, MAV_CMD_NAV_LOITER_TO_ALT})

# MAV_MISSION_TYPE
MAV_MISSION_TYPE_MISSION = common.MAV_MISSION_TYPE_MISSION


@dataclass(frozen=True)
class MissionItem:
    """One mission item. ``x``/``y`` are latitude/longitude in degrees·1e7 (integers) for
    global frames, as MISSION_ITEM_INT carries them; ``z`` is altitude in metres."""

    seq: int
    frame: int
    command: int
    current: int = 0
    autocontinue: int = 1
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    x: int = 0
    y: int = 0
    z: float = 0.0
    mission_type: int = MAV_MISSION_TYPE_MISSION
    # What the item is for in the plan (e.g. "correction 417", "arc", "home"): not sent.
    note: str = field(default="", compare=False)

    @property
    def lat(self) -> float:
        return self.x / 1e7

    @property
    def lon(self) -> float:
        return self.y / 1e7

    def with_seq(self, seq: int) -> MissionItem:
        return replace(self, seq=seq)

    @classmethod
    def from_wire(cls, msg: Any, x: int, y: int) -> MissionItem:
        """The item a MISSION_ITEM(_INT) message carries, with ``x``/``y`` already in the
        stored integer units (how a legacy float message's position is scaled, and whether it
        fits, is the receiver's to decide: the ground station and the vehicle differ)."""
        return cls(
            seq=int(msg.seq),
            frame=int(msg.frame),
            command=int(msg.command),
            current=int(msg.current),
            autocontinue=int(msg.autocontinue),
            param1=float(msg.param1),
            param2=float(msg.param2),
            param3=float(msg.param3),
            param4=float(msg.param4),
            x=int(x),
            y=int(y),
            z=float(msg.z),
            mission_type=int(getattr(msg, "mission_type", 0)),
        )


@dataclass(frozen=True)
class MissionFile:
    """What a mission file (.plan, .waypoints) gives back: the items as the firmware stores them
    (ArduPilot: home at seq 0; PX4: no home item), the firmware, home, and the cruise speed where
    the format carries one."""

    items: tuple[MissionItem, ...]
    firmware: str  # "ardupilot" | "px4"
    home: tuple[float, float, float]  # lat, lon (deg), alt (m AMSL)
    cruise_speed: float | None = None
