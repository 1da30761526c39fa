"""policy.json: a contingency policy's missions and switches as one file (docs/policy-json.md).

``plan --policy`` writes it beside the missions; the ground station in the loop (``fly``) reads
it with :func:`read_policy`. It carries every mission's items, so that what is flown does not
depend on re-reading the .plan files, and a fingerprint of the scenario the policy was made
for, which :func:`read_policy` checks when it is given one.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path
from typing import Any

from gcs_planner.aircraft.profile import FIRMWARES
from gcs_planner.core.contingency import Policy, PolicyValue
from gcs_planner.errors import InputError
from gcs_planner.mission.builder import ALTITUDE_FRAMES, END_ACTIONS, Mission
from gcs_planner.mission.items import MissionItem
from gcs_planner.mission.policy_missions import PolicyMissions, Switch
from gcs_planner.runtime.atomic import write_atomic
from gcs_planner.scenario.model import Kind, Origin, Scenario

FORMAT = "gcs-planner-policy"
VERSION = 1
ITEM_INTS = ("seq", "frame", "command", "current", "autocontinue", "x", "y", "mission_type")
ITEM_FLOATS = ("param1", "param2", "param3", "param4", "z")


def fingerprint(scenario: Scenario) -> dict[str, Any]:
    """What identifies the scenario a policy was made for: its name, source and point count,
    and a SHA-256 over every point's id, coordinates (exact float text), kind and whether it is
    unreliable: any change to the points changes the hash."""
    rows = [
        [
            str(scenario.ids[i]),
            *(repr(float(c)) for c in scenario.xyz[i]),
            Kind(int(scenario.kind[i])).name,
            bool(scenario.unreliable[i]),
        ]
        for i in range(scenario.n)
    ]
    digest = hashlib.sha256(json.dumps(rows, separators=(",", ":")).encode()).hexdigest()
    return {
        "name": scenario.name,
        "source": scenario.source,
        "points": scenario.n,
        "points_sha256": digest,
    }


def _number(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None  # JSON has no NaN: null


def value_to_dict(value: PolicyValue) -> dict[str, Any]:
    return {
        "length": value.length,
        "corrections": value.corrections,
        "probability": value.probability,
        "expected_length_arrived": _number(value.expected_length_arrived),
        "expected_flown": _number(value.expected_flown),
    }


def tree_to_dict(scenario: Scenario, policy: Policy) -> dict[str, Any]:
    """The tree as a table of nodes (point ids; children by index), equal subtrees once."""
    nodes: list[dict[str, Any]] = []
    index: dict[tuple, int] = {}
    seen: dict[int, int] = {}  # id(node) -> index: a shared node is walked once

    def add(node: Policy) -> int:
        if id(node) in seen:
            return seen[id(node)]
        kids = None if node.leaf else (add(node.on_success), add(node.on_failure))
        key = (node.points, kids)
        if key not in index:
            index[key] = len(nodes)
            entry: dict[str, Any] = {"points": [scenario.ids[j] for j in node.points]}
            if kids is not None:
                entry["on_success"], entry["on_failure"] = kids
            nodes.append(entry)
        seen[id(node)] = index[key]
        return index[key]

    return {"root": add(policy), "nodes": nodes}


def mission_to_dict(name: str, mission: Mission, files: dict[str, str]) -> dict[str, Any]:
    o = mission.origin
    return {
        "name": name,
        "files": files,
        "route": list(mission.route),
        "point_seqs": [[pid, seq] for pid, seq in mission.point_seqs],
        "firmware": mission.firmware,
        "home": list(mission.home),
        "cruise_speed": mission.cruise_speed,
        "turn_radius": mission.turn_radius,
        "loiter_param": None if mission.loiter_param is None else list(mission.loiter_param),
        "acceptance_radius": mission.acceptance_radius,
        "origin": {"lat": o.lat, "lon": o.lon, "alt": o.alt},
        "origin_is_default": mission.origin_is_default,
        "altitude_frame": mission.altitude_frame,
        "at_end": mission.at_end,
        "items": [
            {**{k: getattr(it, k) for k in (*ITEM_INTS, *ITEM_FLOATS)}, "note": it.note}
            for it in mission.items
        ],
    }


def policy_to_dict(
    scenario: Scenario,
    policy: Policy,
    missions: PolicyMissions,
    value: PolicyValue,
    files: dict[str, dict[str, str]] | None = None,
    route: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """The policy.json content. ``files``: per mission, format -> file name written beside it;
    ``route``: what the policy was made from (its points and value), shown to the reader."""
    files = files or {}
    return {
        "format": FORMAT,
        "version": VERSION,
        "scenario": fingerprint(scenario),
        "parameters": scenario.params.to_dict(),
        "value": value_to_dict(value),
        "route": route,
        "tree": tree_to_dict(scenario, policy),
        "primary": missions.primary,
        "missions": [mission_to_dict(n, m, files.get(n, {})) for n, m in missions.missions.items()],
        "switches": [
            {
                "mission": s.mission,
                "point": s.point,
                "outcome": "failure",
                "item": s.item,
                "to_mission": s.to_mission,
                "resume_item": s.resume_item,
            }
            for s in missions.switches
        ],
    }


def dumps_policy(data: dict[str, Any]) -> str:
    return json.dumps(data, indent=1, allow_nan=False) + "\n"


def write_policy(
    path: str | os.PathLike[str],
    scenario: Scenario,
    policy: Policy,
    missions: PolicyMissions,
    value: PolicyValue,
    files: dict[str, dict[str, str]] | None = None,
    route: dict[str, Any] | None = None,
) -> Path:
    """Write policy.json atomically (see :func:`policy_to_dict`)."""
    data = policy_to_dict(scenario, policy, missions, value, files=files, route=route)
    return write_atomic(path, dumps_policy(data))


# ---------------------------------------------------------------------------------------------
# Reading


class _Reader:
    """Typed access to the file's fields; each refusal names the file and the field."""

    def __init__(self, source: str) -> None:
        self.source = source

    def bad(self, field: str, message: str) -> InputError:
        return InputError(message, file=self.source, field=field)

    def get(self, obj: Any, key: str, field: str, kind: type | tuple, what: str) -> Any:
        if not isinstance(obj, dict) or key not in obj:
            raise self.bad(field, f"missing ({what} expected)")
        v = obj[key]
        ok = isinstance(v, kind) and not (isinstance(v, bool) and bool not in _tuple(kind))
        if kind in (float, (int, float)) and ok:
            ok = math.isfinite(v)
        if not ok:
            raise self.bad(field, f"must be {what}, got {v!r}")
        return v


def _tuple(kind: type | tuple) -> tuple:
    return kind if isinstance(kind, tuple) else (kind,)


NUM = (int, float)


def _item(r: _Reader, d: Any, field: str) -> MissionItem:
    if not isinstance(d, dict):
        raise r.bad(field, "must be an object")
    ints = {k: r.get(d, k, f"{field}.{k}", int, "a whole number") for k in ITEM_INTS}
    floats = {k: float(r.get(d, k, f"{field}.{k}", NUM, "a number")) for k in ITEM_FLOATS}
    note = d.get("note", "")
    return MissionItem(**ints, **floats, note=note if isinstance(note, str) else "")


def _mission(r: _Reader, d: Any, field: str) -> tuple[str, Mission]:
    if not isinstance(d, dict):
        raise r.bad(field, "must be an object")
    name = r.get(d, "name", f"{field}.name", str, "a mission name")
    items_raw = r.get(d, "items", f"{field}.items", list, "a list of mission items")
    items = tuple(_item(r, it, f"{field}.items[{k}]") for k, it in enumerate(items_raw))
    for k, it in enumerate(items):
        if it.seq != k:
            raise r.bad(f"{field}.items[{k}].seq", f"must be {k} (items in order), got {it.seq}")
    firmware = r.get(d, "firmware", f"{field}.firmware", str, "a firmware name")
    if firmware not in FIRMWARES:
        raise r.bad(f"{field}.firmware", f"must be one of {', '.join(FIRMWARES)}")
    frame = r.get(d, "altitude_frame", f"{field}.altitude_frame", str, "an altitude frame")
    if frame not in ALTITUDE_FRAMES:
        raise r.bad(f"{field}.altitude_frame", f"must be one of {', '.join(ALTITUDE_FRAMES)}")
    at_end = r.get(d, "at_end", f"{field}.at_end", str, "an end action")
    if at_end not in END_ACTIONS:
        raise r.bad(f"{field}.at_end", f"must be one of {', '.join(END_ACTIONS)}")
    home = r.get(d, "home", f"{field}.home", list, "[lat, lon, alt]")
    if len(home) != 3 or not all(isinstance(x, NUM) and not isinstance(x, bool) for x in home):
        raise r.bad(f"{field}.home", "must be [lat, lon, alt], three numbers")
    route = r.get(d, "route", f"{field}.route", list, "a list of point ids")
    if len(route) < 2 or not all(isinstance(p, str) for p in route):
        raise r.bad(f"{field}.route", "must list the point ids from A to B")
    seqs_raw = r.get(d, "point_seqs", f"{field}.point_seqs", list, "[point id, seq] pairs")
    seqs = []
    for k, pair in enumerate(seqs_raw):
        ok = isinstance(pair, list) and len(pair) == 2 and isinstance(pair[0], str)
        if not ok or isinstance(pair[1], bool) or not isinstance(pair[1], int):
            raise r.bad(f"{field}.point_seqs[{k}]", "must be [point id, seq]")
        if not 0 <= pair[1] < len(items):
            raise r.bad(f"{field}.point_seqs[{k}]", f"seq {pair[1]} is not an item of the mission")
        seqs.append((pair[0], pair[1]))
    if [pid for pid, _ in seqs] != route:
        raise r.bad(f"{field}.point_seqs", "must name the route's points in its order")
    loiter = d.get("loiter_param")
    if loiter is not None and not (
        isinstance(loiter, list)
        and len(loiter) == 2
        and isinstance(loiter[0], str)
        and isinstance(loiter[1], NUM)
        and not isinstance(loiter[1], bool)
    ):
        raise r.bad(f"{field}.loiter_param", "must be null or [parameter name, value]")
    origin = r.get(d, "origin", f"{field}.origin", dict, "an object {lat, lon, alt}")
    org = Origin(
        *(
            float(r.get(origin, k, f"{field}.origin.{k}", NUM, "a number"))
            for k in ("lat", "lon", "alt")
        )
    )
    num = {
        k: float(r.get(d, k, f"{field}.{k}", NUM, "a number"))
        for k in ("cruise_speed", "turn_radius", "acceptance_radius")
    }
    mission = Mission(
        items=items,
        firmware=firmware,
        home=tuple(float(x) for x in home),
        loiter_param=None if loiter is None else (loiter[0], float(loiter[1])),
        origin=org,
        origin_is_default=bool(d.get("origin_is_default", False)),
        altitude_frame=frame,
        at_end=at_end,
        route=tuple(route),
        point_seqs=tuple(seqs),
        **num,
    )
    return name, mission


def _switch(r: _Reader, d: Any, field: str, missions: dict[str, Mission]) -> Switch:
    get = {
        k: r.get(d, k, f"{field}.{k}", kind, what)
        for k, kind, what in (
            ("mission", str, "a mission name"),
            ("point", str, "a point id"),
            ("outcome", str, '"failure"'),
            ("item", int, "an item seq"),
            ("to_mission", str, "a mission name"),
            ("resume_item", int, "an item seq"),
        )
    }
    if get["outcome"] != "failure":
        raise r.bad(f"{field}.outcome", f'must be "failure", got {get["outcome"]!r}')
    for k in ("mission", "to_mission"):
        if get[k] not in missions:
            raise r.bad(f"{field}.{k}", f"names no mission of the file: {get[k]!r}")
    flown, to = missions[get["mission"]], missions[get["to_mission"]]
    for k, m in (("mission", flown), ("to_mission", to)):
        if get["point"] not in m.route:
            raise r.bad(f"{field}.point", f"point {get['point']!r} is not on mission {get[k]!r}")
    if get["item"] != flown.seq_of(get["point"]):
        raise r.bad(f"{field}.item", f"must be the seq of point {get['point']}'s waypoint")
    if not flown.seq_of(get["point"]) < get["resume_item"] < len(to.items):
        raise r.bad(f"{field}.resume_item", "must be an item of to_mission after the point's")
    del get["outcome"]
    return Switch(**get)


def load_policy_dict(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The JSON object of a policy file, its format and version checked."""
    from gcs_planner.mission.plan_json import read_json

    data = read_json(path, "policy JSON")
    r = _Reader(str(path))
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise r.bad("format", f'not a gcs-planner policy (expected "format": "{FORMAT}")')
    if data.get("version") != VERSION:
        raise r.bad("version", f"unsupported policy version {data.get('version')!r}")
    return data


def check_scenario(data: dict[str, Any], scenario: Scenario, source: str = "") -> None:
    """Refuse a policy made for another scenario (its fingerprint differs)."""
    r = _Reader(source)
    got = r.get(data, "scenario", "scenario", dict, "the scenario's fingerprint")
    want = fingerprint(scenario)
    for key in ("points", "points_sha256"):
        if got.get(key) != want[key]:
            raise r.bad(
                f"scenario.{key}",
                f"the policy was made for scenario {got.get('name')!r} "
                f"({got.get('points')} points), not for {scenario.name!r} ({scenario.n} points"
                + (", other ids, coordinates or kinds)" if key == "points_sha256" else ")"),
            )


def read_policy(path: str | os.PathLike[str], scenario: Scenario | None = None) -> PolicyMissions:
    """The missions and switches of a policy.json; with ``scenario``, refused unless the file
    was made for it. A bad file is InputError naming the file and the field."""
    data = load_policy_dict(path)
    r = _Reader(str(path))
    if scenario is not None:
        check_scenario(data, scenario, str(path))
    raw = r.get(data, "missions", "missions", list, "a list of missions")
    missions: dict[str, Mission] = {}
    for k, d in enumerate(raw):
        name, mission = _mission(r, d, f"missions[{k}]")
        if name in missions:
            raise r.bad(f"missions[{k}].name", f"mission {name!r} is named twice")
        missions[name] = mission
    primary = r.get(data, "primary", "primary", str, "a mission name")
    if primary not in missions:
        raise r.bad("primary", f"names no mission of the file: {primary!r}")
    raw_sw = r.get(data, "switches", "switches", list, "a list of switches")
    switches = tuple(_switch(r, d, f"switches[{k}]", missions) for k, d in enumerate(raw_sw))
    seen = set()
    for k, s in enumerate(switches):
        if (s.mission, s.point) in seen:
            raise r.bad(f"switches[{k}]", f"a second switch for {s.mission} at point {s.point}")
        seen.add((s.mission, s.point))
    return PolicyMissions(primary, missions, switches)
