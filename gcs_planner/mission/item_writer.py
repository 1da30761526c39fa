"""Mission items written in flight order: each numbered by its place in the mission, each position
turned from the plan's local metres into latitude, longitude (degrees·1e7) and the altitude of
the mission's altitude frame."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from gcs_planner.mission.items import MAV_CMD_NAV_WAYPOINT, MissionItem
from gcs_planner.scenario.georef import LocalFrame


def deg_e7(deg: float) -> int:
    """Degrees as MISSION_ITEM_INT carries them (degrees·1e7, rounded)."""
    return int(round(float(deg) * 1e7))


@dataclass
class ItemWriter:
    """The items of one mission as they are written. ``frame``: the MAV_FRAME of the positions
    the route flies; ``alt_offset``: metres taken off an altitude above mean sea level (home's
    altitude in the relative frame, else 0)."""

    local: LocalFrame
    frame: int
    alt_offset: float = 0.0
    items: list[MissionItem] = field(default_factory=list)

    def add(self, command: int, frame: int, note: str, **fields: Any) -> int:
        """Append an item (params and z as floats) and return its seq."""
        for name in ("param1", "param2", "param3", "param4", "z"):
            if name in fields:
                fields[name] = float(fields[name])
        self.items.append(
            MissionItem(seq=len(self.items), frame=frame, command=command, note=note, **fields)
        )
        return self.items[-1].seq

    def at(self, p: np.ndarray) -> dict[str, Any]:
        """x, y, z of the local point ``p`` (m) as the mission's items carry them."""
        lat, lon, alt = self.local.to_geodetic(*p)
        return {"x": deg_e7(lat), "y": deg_e7(lon), "z": float(alt) - self.alt_offset}

    def waypoint(self, note: str, p: np.ndarray, **params: float) -> int:
        """A NAV_WAYPOINT on the local point ``p`` in the route's frame; its seq."""
        return self.add(MAV_CMD_NAV_WAYPOINT, self.frame, note, **params, **self.at(p))
