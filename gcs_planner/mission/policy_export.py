"""``plan --policy``: the chosen route replanned on failure (core/contingency.py) and written as
missions, policy.json and pictures, beside what ``plan --out`` writes.

Everything is computed and rendered before anything is written, and written as one folder
(atomic.write_folder_atomic): an error or an interruption leaves no part of it.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from gcs_planner.aircraft.autopilot import keeps_home_item
from gcs_planner.core.contingency import Policy, PolicyValue, evaluate
from gcs_planner.core.policy_front import (
    EXACT_MAX_POINTS,
    PolicyPoint,
    exact_policy_front,
    replanned_front,
)
from gcs_planner.core.replan import (
    DEFAULT_POLICY_LEVELS,
    replan_on_failure,
    search_continuation,
    success_path,
)
from gcs_planner.core.switch_room import SwitchRoom
from gcs_planner.errors import GcsPlannerError
from gcs_planner.mission.onboard_files import ONBOARD_FILES, render_onboard
from gcs_planner.mission.policy_build import (
    MissionPath,
    PathSwitch,
    assemble,
    policy_mission_plans,
)
from gcs_planner.mission.policy_file import dumps_policy, policy_to_dict, value_to_dict
from gcs_planner.mission.policy_missions import PolicyMissions
from gcs_planner.mission.qgc_plan import dumps_plan
from gcs_planner.mission.waypoints import dumps_waypoints
from gcs_planner.scenario.model import Kind

if TYPE_CHECKING:
    from gcs_planner.core.planner import Plan
    from gcs_planner.scenario.model import Scenario

POLICY_FILE = "policy.json"
TREE_PNG = "policy_tree.png"
FRONT_PNG = "policy_front.png"
# The mission files: "<mission name>.plan" / ".waypoints" (names from policy_build).
MISSION_FILE = re.compile(r"(primary|branch-[A-Za-z0-9._-]+)\.(plan|waypoints)")


@dataclass(frozen=True)
class PolicyExport:
    """The chosen route's policy and what is written of it."""

    route_index: int
    policy: Policy
    value: PolicyValue  # of the policy
    route_value: PolicyValue  # of the chosen route flown as a fixed route
    missions: PolicyMissions
    paths: list[tuple[MissionPath, dict]]  # each mission's path and one-route plan
    switches: list[PathSwitch]
    # (front index, route value, policy value) for every route of the front
    front: list[tuple[int, PolicyValue, PolicyValue]]
    # "mission <name>: point <id> is likely missed ..." for each branch that fails the capture
    # check (the primary is the chosen route, which the plan checks)
    capture_warnings: tuple[str, ...] = ()
    # The policy front: the non-dominated of the front's routes and their replanned policies,
    # or, on scenarios of at most EXACT_MAX_POINTS correction points, the exact front over all
    # policies (``exact``).
    policy_front: tuple[PolicyPoint, ...] = ()
    exact: bool = False
    levels: int = 1
    unproven_branches: tuple[str, ...] = ()  # failed points whose continuation is not proven
    # The run-out kept after every point so that a switch fits in it (core/switch_room.py);
    # None when the policy was planned without one (straight legs, or a library caller).
    switch_room: SwitchRoom | None = None


def replaceable(out: str | os.PathLike[str], route_files: tuple[str, ...]) -> list[str]:
    """The names an earlier ``plan --policy`` may have left in ``out``: ``route_files`` (what
    ``plan --out`` writes), policy.json, the pictures and existing mission files."""
    names = [*route_files, POLICY_FILE, TREE_PNG, FRONT_PNG, *ONBOARD_FILES]
    if Path(out).is_dir():
        names += [e.name for e in os.scandir(out) if MISSION_FILE.fullmatch(e.name)]
    return names


def make_policy(
    result: Plan, plan: dict, *, levels: int = DEFAULT_POLICY_LEVELS, **mission_options: Any
) -> PolicyExport:
    """Replan the chosen route (and, for the policy front and its picture, every route of the
    front) on failure, each failure branch the continuation the planner chooses from the state
    reached, as this plan chose its route (``core/replan.py``, ``levels`` deep), and build the
    missions of the chosen one."""
    scenario = result.scenario
    find = search_continuation(
        scenario, choice=result.choice, min_probability=result.min_probability
    )
    front = []
    policies: list[Policy] = []
    unproven: list[str] = []
    chosen: tuple[Policy, PolicyValue, PolicyValue] | None = None
    for k, route in enumerate(result.routes):
        try:
            replanned = replan_on_failure(scenario, route, continuation=find, levels=levels)
        except GcsPlannerError as exc:
            raise GcsPlannerError(f"plan --policy: {exc}") from None
        policy = replanned.policy
        policies.append(policy)
        pv = evaluate(scenario, policy)
        rv = evaluate(scenario, Policy.from_route(scenario, route))
        front.append((k, rv, pv))
        if k == result.chosen:
            chosen = (policy, pv, rv)
            unproven = replanned.unproven
    assert chosen is not None
    policy, value, route_value = chosen
    corrections = sum(1 for k in scenario.kind if Kind(int(k)) in (Kind.V, Kind.H))
    exact = corrections <= EXACT_MAX_POINTS
    pfront = (
        exact_policy_front(scenario)
        if exact
        else replanned_front(scenario, result.routes, policies)
    )
    paths, switches = policy_mission_plans(scenario, policy, plan)
    missions = assemble(scenario, paths, switches, **mission_options)
    warnings = tuple(
        f"mission {p.name}: {w}"
        for p, _ in paths[1:]
        if (w := _capture_warning(scenario, p.points)) is not None
    )
    return PolicyExport(
        result.chosen, policy, value, route_value, missions, paths, switches, front, warnings,
        tuple(pfront), exact, levels, tuple(unproven),
    )  # fmt: skip


def _capture_warning(scenario: Scenario, points: tuple[int, ...]) -> str | None:
    """The plan's capture check (core/capture.py) over a branch mission's whole path: the
    worst error on arrival over its correction outcomes against the capture radius."""
    from gcs_planner.aircraft.profile import TRACKING_ALLOWANCE_M
    from gcs_planner.core.bnb.flown import flown_route
    from gcs_planner.core.capture import capture_check, capture_warning

    s = scenario
    stops = flown_route(s, points).stops
    check = capture_check(stops, s.error_unit, s.capture_radius, TRACKING_ALLOWANCE_M, s.params)
    return capture_warning(check)


def render_policy_files(result: Plan, plan: dict, exp: PolicyExport) -> list[tuple[str, Any]]:
    """(file name, content) of the mission files, policy.json and the two pictures."""
    from gcs_planner.mission import policy_pictures

    files: dict[str, dict[str, str]] = {}
    out: list[tuple[str, Any]] = []
    for name, mission in exp.missions.missions.items():
        files[name] = {"plan": f"{name}.plan"}
        out.append((f"{name}.plan", dumps_plan(mission)))
        # PX4 missions have no .waypoints (mission/waypoints.py says why).
        if keeps_home_item(mission.firmware):
            files[name]["waypoints"] = f"{name}.waypoints"
            out.append((f"{name}.waypoints", dumps_waypoints(mission)))
    route = result.routes[exp.route_index]
    made_from = {
        "front_index": exp.route_index,
        "points": route.ids(),
        "method": f"replan_on_failure, {exp.levels} level(s), continuations planned from "
        "each failure state and chosen as the plan chooses",
        "value": value_to_dict(exp.route_value),
    }
    data = policy_to_dict(
        result.scenario, exp.policy, exp.missions, exp.value, files=files, route=made_from
    )
    if exp.switch_room is not None:
        data["switch_room"] = exp.switch_room.to_dict()
    onboard, data["onboard"] = render_onboard(result.scenario, exp.missions)
    out += onboard
    out.append((POLICY_FILE, dumps_policy(data)))
    s = result.scenario
    title = (
        f"{s.name}: policy from route {exp.route_index}, P {exp.value.probability:.3f} "
        f"(route {exp.route_value.probability:.3f}), worst case {exp.value.length / 1000:.2f} km"
    )
    out.append((TREE_PNG, policy_pictures.tree_png(plan, exp.paths, exp.switches, title)))
    rows = [(k, rv.length, rv.probability, pv.length, pv.probability) for k, rv, pv in exp.front]
    out.append(
        (
            FRONT_PNG,
            policy_pictures.policy_front_png(
                rows,
                exp.route_index,
                f"{s.name}: routes of the front and their policies (F3 vs F1)",
            ),
        )
    )
    return out


def check_policy_exportable(
    exp: PolicyExport, min_probability: float, allow_risky: bool
) -> str | None:
    """As policy.check_exportable, for the policy's probability of arriving: RiskyRouteError
    below ``min_probability`` unless allowed, a warning below the safe default."""
    from gcs_planner.core.choose import DEFAULT_MIN_PROBABILITY, PROB_EPS, RiskyRouteError

    p = exp.value.probability
    said = (
        f"the policy from route {exp.route_index} arrives with probability {p:.4f} (lost with "
        f"probability {1 - p:.4f})"
    )
    if p < min_probability - PROB_EPS and not allow_risky:
        raise RiskyRouteError(
            f"{said}, below --min-probability {min_probability:g}; not exported: pass "
            "--allow-risky to export it anyway, or lower --min-probability"
        )
    if p < DEFAULT_MIN_PROBABILITY - PROB_EPS:
        return f"{said}; it is below the safe default {DEFAULT_MIN_PROBABILITY:g}"
    return None


def _m(x: float) -> str:
    return f"{x:,.1f}" if math.isfinite(x) else "-"


def summary(result: Plan, exp: PolicyExport) -> str:
    """What the policy buys: its P, worst-case and expected length against the chosen route's
    and the best route's of the front (the likeliest to arrive, then the shortest)."""
    best_k = max(
        range(len(exp.front)), key=lambda i: (exp.front[i][1].probability, -exp.front[i][1].length)
    )
    best = exp.front[best_k][1]
    rows = [
        (f"policy (route {exp.route_index} replanned)", exp.value),
        (f"chosen route {exp.route_index}", exp.route_value),
        (f"most reliable route {best_k}", best),
    ]
    out = [
        f"contingency policy: {len(exp.missions.missions)} mission(s), "
        f"{len(exp.missions.switches)} switch(es) on a failed fix",
        f"  {'':34} {'P arrive':>9} {'worst-case m':>13} {'expected m':>11} {'exp. flown m':>12}",
    ]
    for label, v in rows:
        out.append(
            f"  {label:34} {v.probability:>9.4f} {_m(v.length):>13} "
            f"{_m(v.expected_length_arrived):>11} {_m(v.expected_flown):>12}"
        )
    gain = exp.value.probability - exp.route_value.probability
    out.append(
        f"  the policy arrives {gain:+.4f} more often than the chosen route for at most "
        f"{exp.value.length - exp.route_value.length:+,.1f} m in its longest outcome"
        f" ({exp.value.probability - best.probability:+.4f} against the most reliable route)"
    )
    if exp.switch_room is not None:
        out.append(f"  {exp.switch_room.describe()}")
    out += _policy_front_lines(exp)
    for s in exp.missions.switches:
        out.append(
            f"  switch: {s.mission} item {s.item} (point {s.point}) fails -> "
            f"{s.to_mission} from item {s.resume_item}"
        )
    return "\n".join(out)


def _policy_front_lines(exp: PolicyExport) -> list[str]:
    """The policy front beside the route front, and what it proves."""
    if exp.exact:
        how = "exact over every policy (dynamic programming over flight states)"
    else:
        how = (
            "the non-dominated of the front's routes and their replanned policies; not proven "
            f"optimal over all policies (exact up to {EXACT_MAX_POINTS} correction points)"
        )
    out = [f"policy front ({how}):"]
    out.append(f"  {'F1 worst-case m':>16} {'F2':>4} {'F3 P arrive':>12} {'expected m':>11}  kind")
    for pt in exp.policy_front:
        v = pt.value
        kind = "route" if _is_route(pt.policy) else "policy"
        out.append(
            f"  {_m(v.length):>16} {v.corrections:>4} {v.probability:>12.4f} "
            f"{_m(v.expected_length_arrived):>11}  {kind}"
        )
    if exp.unproven_branches:
        out.append(
            "  continuations not proven optimal within their time limit, at: "
            + ", ".join(exp.unproven_branches)
        )
    return out


def _is_route(policy: Policy) -> bool:
    """Whether the policy never branches (both outcomes continue the same way everywhere)."""
    node = policy
    while node.on_success is not None:
        if node.on_failure is not node.on_success and _points(node.on_failure) != _points(
            node.on_success
        ):
            return False
        node = node.on_success
    return True


def _points(node: Policy) -> tuple[int, ...]:
    """The whole path below ``node`` along its success outcomes, its first point included."""
    return (node.points[0], *success_path(node))
