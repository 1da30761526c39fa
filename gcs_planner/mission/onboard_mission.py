"""A contingency policy as ONE mission the vehicle holds from take-off: the primary, then each
branch's own items after it, so that a switch is only a jump to another item
(docs/flying-policies.md, "Switching on board").

Layout: the primary mission whole (home, the speed item, A .. B, its end action), then, for each
switch that changes the items flown, a **segment**: the branch's items from its resume item to
its own end action. A segment lies behind the end action of the one before it, so the aircraft
never falls through into it: a NAV_LOITER_UNLIM never completes, and a NAV_LAND is never
verified (ArduPlane ``commands_logic.cpp``: ``verify_land`` stays false until the aircraft is on
the ground and disarms). A NAV_RETURN_TO_LAUNCH does complete (``verify_RTL``: home reached), and
the mission then goes on with its next item; so a segment that ends with one gets a
NAV_LOITER_UNLIM at home behind it, which holds the aircraft where RTL would have loitered.

A branch that flies the same items as the mission it leaves (only its later switches differ)
has no segment of its own: it is flown on its parent's. Every mission's item ``seq`` is then at
a known onboard index (:meth:`OnboardMission.index_of`), and each switch says which onboard
item to make current (its ``resume``) or, when the aircraft has already gone past the shared
run-out, the one after it (``late``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from gcs_planner.errors import GcsPlannerError
from gcs_planner.mission.builder import Mission
from gcs_planner.mission.items import (
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    POSITION_COMMANDS,
    MissionItem,
)
from gcs_planner.mission.policy_missions import PolicyMissions, Switch

ONBOARD_PLAN = "onboard.plan"
ONBOARD_WAYPOINTS = "onboard.waypoints"


@dataclass(frozen=True)
class Segment:
    """Where mission ``mission``'s items ``base`` .. ``base + count - 1`` lie in the onboard
    mission: from onboard index ``first`` on."""

    mission: str
    first: int
    base: int
    count: int

    def holds(self, seq: int) -> bool:
        return self.base <= seq < self.base + self.count


@dataclass(frozen=True)
class OnboardSwitch:
    """A policy switch in onboard item numbers: when the fix at ``point`` does not take while
    ``mission`` is flown, fly ``to_mission`` from onboard item ``resume`` (the branch's resume
    item) or, if the aircraft already flies past the run-out both share (its current item is
    beyond ``item + 1``), from ``late``. ``jump`` is False for a branch with the same items
    (nothing is set current: the vehicle flies on and follows the branch's later switches)."""

    mission: str
    point: str
    item: int  # onboard index of the point's waypoint in the flown segment
    to_mission: str
    resume: int
    late: int
    jump: bool


@dataclass(frozen=True)
class OnboardMission:
    """The one mission (``mission.items``, seq = onboard index) and its switches."""

    mission: Mission
    segments: dict[str, Segment]  # by mission name; a same-items branch shares its parent's
    switches: tuple[OnboardSwitch, ...]
    primary: str

    def index_of(self, mission: str, seq: int) -> int:
        """The onboard index of item ``seq`` of ``mission``."""
        seg = self.segments[mission]
        if not seg.holds(seq):
            raise KeyError(f"item {seq} of mission {mission!r} is not on board")
        return seg.first + seq - seg.base

    def switch_for(self, mission: str, point: str) -> OnboardSwitch | None:
        for s in self.switches:
            if s.mission == mission and s.point == point:
                return s
        return None

    def mission_at(self, index: int) -> str:
        """The mission whose own segment holds onboard item ``index`` (a same-items branch's
        items are its parent's)."""
        for name, seg in self.segments.items():
            if seg.first <= index < seg.first + seg.count and seg.mission == name:
                return name
        raise KeyError(index)


def _barrier(mission: Mission, items: list[MissionItem]) -> list[MissionItem]:
    """What keeps the aircraft from falling through past a segment's end (module docstring):
    nothing after a loiter or a landing, a NAV_LOITER_UNLIM at home after an RTL."""
    if not items or items[-1].command != MAV_CMD_NAV_RETURN_TO_LAUNCH:
        return []
    last = next((it for it in reversed(items) if it.command in POSITION_COMMANDS), None)
    if last is None:
        raise GcsPlannerError("a mission that ends with RTL has no position item before it")
    lat, lon, _ = mission.home
    hold = MissionItem(
        seq=0, frame=last.frame, command=MAV_CMD_NAV_LOITER_UNLIM,
        param3=float(mission.turn_radius), x=round(lat * 1e7), y=round(lon * 1e7), z=last.z,
        note="hold at home after RTL: the onboard mission's next segment is another branch",
    )  # fmt: skip
    return [hold]


def onboard_mission(policy: PolicyMissions) -> OnboardMission:
    """The policy's missions as one (module docstring). Raises GcsPlannerError for a switch
    whose branch resumes before the part of it already placed (not made by ``plan --policy``)."""
    primary = policy.missions[policy.primary]
    items: list[MissionItem] = list(primary.items)
    items += _barrier(primary, items)
    segments = {policy.primary: Segment(policy.primary, 0, 0, len(primary.items))}
    placed: list[tuple[Switch, bool]] = []
    pending = list(policy.switches)
    # Parents before children: a switch is placed once the mission it leaves has a segment.
    while pending:
        ready = [s for s in pending if s.mission in segments]
        if not ready:
            names = ", ".join(sorted({s.mission for s in pending}))
            raise GcsPlannerError(f"switches from missions never flown: {names}")
        for s in ready:
            pending.remove(s)
            jump = policy.changes_items(s)
            to = s.to_mission
            if to in segments:
                if not segments[to].holds(s.resume_item):
                    raise GcsPlannerError(
                        f"mission {to!r} is entered at item {s.resume_item}, before its items "
                        "placed on board"
                    )
            elif not jump:
                parent = segments[s.mission]
                segments[to] = replace(parent, mission=parent.mission)
            else:
                branch = policy.missions[to]
                own = list(branch.items[s.resume_item :])
                first = len(items)
                items += own
                items += _barrier(branch, own)
                segments[to] = Segment(to, first, s.resume_item, len(own))
            placed.append((s, jump))
    numbered = tuple(it.with_seq(k) for k, it in enumerate(items))
    one = replace(primary, items=numbered)
    switches = []
    for s, jump in placed:
        seg, to = segments[s.mission], segments[s.to_mission]
        if not seg.holds(s.item):
            raise GcsPlannerError(f"point {s.point} of mission {s.mission!r} is not on board")
        resume = to.first + s.resume_item - to.base
        late = min(resume + 1, to.first + to.count - 1)
        item = seg.first + s.item - seg.base
        switches.append(OnboardSwitch(s.mission, s.point, item, s.to_mission, resume, late, jump))
    return OnboardMission(one, segments, tuple(switches), policy.primary)
