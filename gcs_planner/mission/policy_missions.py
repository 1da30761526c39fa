"""A contingency policy as missions a ground station switches between (docs/model.md,
"Contingency policies").

A policy is flown by switching missions in flight: the vehicle flies the primary mission (the
outcome path on which every fix takes); when the correction at an unreliable point fails and
the policy branches there, the ground station uploads that branch's mission and sets its
current item. Each branch mission is a whole mission from A (the outcome path that leads to it,
then the branch's continuation), so that its item numbers are those of an ordinary mission and
the autopilot's home and first items are unchanged; the vehicle resumes at the item after the
failed point.

This module holds the structure both ends share: the exporter makes it from a policy
(``plan --policy``, ``policy.json``) and the ground station in the loop (``fly``,
``dry-run --policy``) flies it.
"""

from __future__ import annotations

from dataclasses import dataclass

from gcs_planner.mission.builder import Mission


@dataclass(frozen=True)
class Switch:
    """When the fix at ``point`` fails while ``mission`` is flown, fly ``to_mission`` from its
    item ``resume_item`` on."""

    mission: str  # the mission being flown
    point: str  # id of the unreliable correction point whose failed fix triggers the switch
    item: int  # seq of that point's NAV_WAYPOINT in ``mission``
    to_mission: str  # the mission to upload
    resume_item: int  # seq in ``to_mission`` to set current once it is uploaded and verified


@dataclass(frozen=True)
class PolicyMissions:
    """Every mission of a policy, by name, and the switches between them."""

    primary: str  # the name of the mission uploaded first
    missions: dict[str, Mission]
    switches: tuple[Switch, ...]

    def switch_for(self, mission: str, point: str) -> Switch | None:
        """The switch taken when the fix at ``point`` fails while ``mission`` is flown (None:
        the policy keeps the mission flown)."""
        for s in self.switches:
            if s.mission == mission and s.point == point:
                return s
        return None

    def changes_items(self, switch: Switch) -> bool:
        """Whether ``switch`` changes the items the vehicle flies. False when the mission it
        switches to has the same items as the one flown (the same points after the failure;
        only switches further on differ): the ground station then only follows the other
        mission's switches, and the vehicle's mission needs no upload."""
        return self.missions[switch.mission].items != self.missions[switch.to_mission].items
