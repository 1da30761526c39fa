"""Small rules of flying a policy, each on its own: where the vehicle resumes in a branch
(policy_flight._resume_item), the numbers dry-run --policy reads from policy.json, and when the
live mock's honest time scale ends after the ground station acted (sim/live_vehicle.py)."""

from __future__ import annotations

import json
from types import SimpleNamespace

import pytest
from gcs_planner.sim.live_vehicle import SETTLE_WALL_S, _Window

from gcs_planner.errors import InputError
from gcs_planner.mission.policy_file import FORMAT, VERSION
from gcs_planner.policies.dry_run import policy_probability, policy_switch_room
from gcs_planner.policies.flight import _resume_item

# Missions as item lists: the primary and a branch that shares its first four items.
PRIMARY = ["home", "wp1", "wp2", "fix", "dep", "p5", "p6", "B"]
BRANCH = ["home", "wp1", "wp2", "fix", "dep", "b5", "b6", "b7", "B"]


def test_the_resume_item_is_kept_while_the_vehicle_has_not_passed_it() -> None:
    assert _resume_item(4, None, PRIMARY, BRANCH) == 4  # vehicle's item unknown
    assert _resume_item(4, 3, PRIMARY, BRANCH) == 4
    assert _resume_item(4, 4, PRIMARY, BRANCH) == 4


def test_a_vehicle_past_the_resume_item_goes_on_where_the_missions_agree() -> None:
    # Flying to item 5 ("p5" vs "b5"): items 0..4 are shared, so it flies on from where it is
    # to the branch's first item of its own, not back to the departure waypoint 4.
    assert _resume_item(4, 5, PRIMARY, BRANCH) == 5
    # Gone further along the primary than the shared part: still the branch's first own item.
    assert _resume_item(4, 7, PRIMARY, BRANCH) == 5
    # A branch that differs from item 2 on: the resume item itself, never an earlier one.
    other = ["home", "wp1", "x2", "x3", "x4", "x5"]
    assert _resume_item(4, 6, PRIMARY, other) == 4


def test_a_vehicle_past_the_resume_item_within_the_shared_items_keeps_its_item() -> None:
    same_start = PRIMARY[:7] + ["b7", "B"]  # shares items 0..6
    assert _resume_item(4, 6, PRIMARY, same_start) == 6


def _policy(tmp_path, **extra) -> str:
    path = tmp_path / "policy.json"
    path.write_text(json.dumps({"format": FORMAT, "version": VERSION, **extra}))
    return str(path)


def test_policy_numbers_are_read_or_named_when_bad(tmp_path) -> None:
    good = _policy(tmp_path, value={"probability": 0.27}, switch_room={"distance_m": 435.0})
    assert policy_probability(good) == pytest.approx(0.27)
    assert policy_switch_room(good) == pytest.approx(435.0)
    none = _policy(tmp_path)
    assert policy_probability(none) is None and policy_switch_room(none) is None
    for section, key, bad in (
        ("value", "probability", 1.5),
        ("value", "probability", "high"),
        ("value", "probability", True),
        ("switch_room", "distance_m", -1),
        ("switch_room", "distance_m", float("nan")),
    ):
        path = _policy(tmp_path, **{section: {key: bad}})
        read = policy_probability if section == "value" else policy_switch_room
        with pytest.raises(InputError) as e:
            read(path)
        assert e.value.field == f"{section}.{key}" and e.value.file == path


def test_the_honest_scale_outlasts_a_set_current_until_the_ground_station_is_quiet() -> None:
    """A set-current whose acknowledgement was lost comes again one timeout later: it must find
    the aircraft where the first did, not a cruise-scale thousand seconds further on."""
    flight = SimpleNamespace(current=5)
    quiet = SimpleNamespace(corrections=())
    fixed = SimpleNamespace(corrections=("a correction",))
    w = _Window(since=100.0, quiet_until=50.0 + SETTLE_WALL_S)
    assert w.settling()
    assert not w.over(flight, 101.0, quiet, now=50.0 + SETTLE_WALL_S / 2)
    # Neither a correction nor the item changing ends it: only the quiet.
    assert not w.over(flight, 102.0, fixed, now=50.1)
    assert w.over(flight, 103.0, quiet, now=50.0 + SETTLE_WALL_S)
    # It outlasts the ground station's resend of the command (gcs_planner/link/protocol.py).
    from gcs_planner.link.protocol import DEFAULT_TIMEOUT_S

    assert SETTLE_WALL_S > DEFAULT_TIMEOUT_S
    # A window opened by a failed fix ends at the next correction, as before.
    fix = _Window(since=100.0)
    assert not fix.settling()
    assert not fix.over(flight, 101.0, quiet, now=0.0)
    assert fix.over(flight, 101.0, fixed, now=0.0)
