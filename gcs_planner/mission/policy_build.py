"""A contingency policy (core/contingency.py) as the missions a ground station switches between
(mission/policy_missions.py).

The **primary** mission is the outcome path on which every fix takes. Wherever a policy's
failure branch differs from its success continuation, a **branch** mission is the whole path
from A that the aircraft flies after that failure: the path that led to the failed point, then
the failure branch, then its success continuations to B. So its items up to the failed point's
waypoint are the parent's, item for item, and its item numbers are those of an ordinary
mission. Branches of branches are made the same way from the branch they leave.

"Differs" is structural: two subtrees differ when their points or any of their branches do.
A failure branch that flies the same points as the success continuation but replans some later
failure differently (its errors differ) is a mission of its own: the same items, other switches.

Every mission is built from the scenario itself: its path flown by ``flown_route`` and its legs
by ``route_to_dict`` from A with the scenario's heading, each leg from the heading the previous
one ended with, which is how the policy evaluator flies each segment from the heading the last
one left (contingency._fly): a mission flies exactly the legs the policy's value was computed on.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from gcs_planner.core.bnb.flown import flown_route
from gcs_planner.core.contingency import Policy, validate
from gcs_planner.errors import GcsPlannerError
from gcs_planner.mission.builder import Mission, build_mission
from gcs_planner.mission.plan_json import route_to_dict
from gcs_planner.mission.policy_missions import PolicyMissions, Switch
from gcs_planner.scenario.model import Scenario

PRIMARY = "primary"


@dataclass(frozen=True)
class MissionPath:
    """One mission of a policy before it is built: its name, its point path (scenario
    indices, A..B), the mission it branches from and the point whose failed fix leads to it
    (None for the primary)."""

    name: str
    points: tuple[int, ...]
    parent: str | None = None
    failed: int | None = None


@dataclass(frozen=True)
class PathSwitch:
    """A switch in scenario indices: ``failed`` fails while ``mission`` is flown -> ``to``."""

    mission: str
    failed: int
    to: str


class _Canon:
    """Structural identity of policy subtrees: equal numbers iff equal points and branches,
    recursively (a policy may share nodes between outcomes, or repeat equal ones)."""

    def __init__(self) -> None:
        self.table: dict[tuple, int] = {}
        self.by_id: dict[int, int] = {}

    def __call__(self, node: Policy) -> int:
        got = self.by_id.get(id(node))  # the policy holds its nodes: ids stay theirs
        if got is None:
            kids = None if node.leaf else (self(node.on_success), self(node.on_failure))
            got = self.table.setdefault((node.points, kids), len(self.table))
            self.by_id[id(node)] = got
        return got


def _safe(point_id: str) -> str:
    """A point id as a mission name and file stem: letters, digits, '.', '_' and '-' only."""
    return re.sub(r"[^A-Za-z0-9._-]", "_", str(point_id)) or "_"


def mission_paths(scenario: Scenario, policy: Policy) -> tuple[list[MissionPath], list[PathSwitch]]:
    """The missions of ``policy`` (primary first, then branches depth first) and the switches
    between them. Raises GcsPlannerError for a malformed policy."""
    validate(scenario, policy)
    canon = _Canon()
    paths: list[MissionPath] = []
    switches: list[PathSwitch] = []
    made: dict[tuple[tuple[int, ...], int], str] = {}
    names: set[str] = set()

    def name_for(failed: int) -> str:
        base = f"branch-{_safe(scenario.ids[failed])}"
        name, k = base, 1
        while name in names:  # the same point failing in another context
            k += 1
            name = f"{base}-{k}"
        names.add(name)
        return name

    def mission(prefix: tuple[int, ...], node: Policy, parent: str | None, failed: int | None):
        # The same subtree after the same path is the same mission (a shared continuation
        # reached through either outcome of an earlier fix).
        key = (prefix, canon(node))
        if key in made:
            return made[key]
        name = PRIMARY if parent is None else name_for(failed)
        names.add(name)
        made[key] = name
        path = list(prefix)
        pending = []
        while True:
            path += node.points[1:]
            if node.leaf:
                break
            if canon(node.on_failure) != canon(node.on_success):
                pending.append((node.points[-1], tuple(path), node.on_failure))
            node = node.on_success
        paths.append(MissionPath(name, tuple(path), parent, failed))
        for point, pre, child in pending:
            switches.append(PathSwitch(name, point, mission(pre, child, name, point)))
        return name

    mission((policy.points[0],), policy, None, None)
    return paths, switches


def path_plan(scenario: Scenario, plan: dict, points: tuple[int, ...]) -> dict[str, Any]:
    """``plan`` with one route, ``points``, flown from A as the policy evaluator flies it: the
    plan's georeference, parameters and vehicle, as the mission builder reads them."""
    route = flown_route(scenario, tuple(int(j) for j in points))
    if not math.isfinite(route.length):
        ids = " ".join(scenario.ids[j] for j in points)
        raise GcsPlannerError(f"the policy's path {ids} has a leg that cannot be flown")
    entry = route_to_dict(scenario, route, route.length)
    return {**plan, "front": [entry], "chosen": 0}


def policy_mission_plans(
    scenario: Scenario, policy: Policy, plan: dict
) -> tuple[list[tuple[MissionPath, dict]], list[PathSwitch]]:
    """Each mission's path with its one-route plan (what the mission and the pictures are made
    from), and the switches."""
    paths, switches = mission_paths(scenario, policy)
    return [(p, path_plan(scenario, plan, p.points)) for p in paths], switches


def policy_missions(
    scenario: Scenario, policy: Policy, plan: dict, **mission_options: Any
) -> PolicyMissions:
    """The primary and branch missions of ``policy`` and the switches between them.

    ``plan`` is the plan dict of ``scenario`` (plan_json.plan_to_dict: its origin, parameters
    and vehicle); ``mission_options`` are :func:`build_mission`'s (firmware, altitude frame,
    end action, ...). Each switch's ``item`` is the seq of the failed point's waypoint in the
    mission flown, and ``resume_item`` the item after that waypoint in the branch: the aircraft
    is at the point when it learns the fix failed, and what follows the waypoint is the
    branch's next leg (its departure waypoint straight on, its helix, arc, or next point).
    """
    plans, switches = policy_mission_plans(scenario, policy, plan)
    return assemble(scenario, plans, switches, **mission_options)


def assemble(
    scenario: Scenario,
    plans: list[tuple[MissionPath, dict]],
    switches: list[PathSwitch],
    **mission_options: Any,
) -> PolicyMissions:
    """Build each mission from its one-route plan and number the switches by its items."""
    missions: dict[str, Mission] = {
        p.name: build_mission(d, route_index=0, **mission_options) for p, d in plans
    }
    out = []
    for s in switches:
        pid = scenario.ids[s.failed]
        flown, to = missions[s.mission], missions[s.to]
        item = flown.seq_of(pid)
        # The branch is the same mission up to the failed point: the vehicle is switched
        # between two missions that agree on everything it has flown.
        if to.seq_of(pid) != item or to.items[: item + 1] != flown.items[: item + 1]:
            raise GcsPlannerError(
                f"mission {s.to} does not repeat {s.mission} up to point {pid} (internal error)"
            )
        out.append(Switch(s.mission, pid, item, s.to, item + 1))
    return PolicyMissions(PRIMARY, missions, tuple(out))
