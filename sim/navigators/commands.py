"""The mission as the navigators read it: the MAVLink commands they act on, one stored item in the
local frame (:class:`NavCommand`) and what the autopilot did with it (:class:`Event`)."""

from __future__ import annotations

from dataclasses import dataclass

# MAV_CMD (common.xml)
NAV_WAYPOINT = 16
NAV_LOITER_UNLIM = 17
NAV_LOITER_TURNS = 18
NAV_LOITER_TIME = 19
NAV_RETURN_TO_LAUNCH = 20
NAV_LAND = 21
NAV_TAKEOFF = 22
NAV_LOITER_TO_ALT = 31
DO_CHANGE_SPEED = 178
LOITERS = frozenset({NAV_LOITER_UNLIM, NAV_LOITER_TURNS, NAV_LOITER_TIME, NAV_LOITER_TO_ALT})


@dataclass(frozen=True)
class NavCommand:
    """One mission item the guidance acts on, its position in the local frame when it has one."""

    seq: int
    command: int
    pos: tuple[float, float, float] | None
    params: tuple[float, float, float, float]


@dataclass(frozen=True)
class Event:
    """Something the autopilot did: ``kind`` "reached", "skipped", "altitude" or "end";
    ``sample`` the index of the track sample at that moment."""

    t: float
    sample: int
    seq: int
    kind: str
    text: str = ""
