"""Switching a contingency policy on board (docs/flying-policies.md, "Switching on board"): the
one onboard mission (mission/onboard_mission.py), the applet policy.lua
(mission/onboard_applet.py) loaded in a real Lua 5.3 (lupa) by the mock's scripting host
(sim/scripting.py), and what the applet does with each report, on the hand-made scenario of
tests/support/policy_scenario.py (the primary A H1 P2 B, the branch after P2 over V3)."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest
from gcs_planner.sim.scripting import BINDINGS, MISSION_RUNNING, MISSION_STOPPED, ScriptHost
from support.policy_scenario import policy_missions, policy_scenario

from gcs_planner.mission import onboard_applet
from gcs_planner.mission.items import (
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MissionItem,
)
from gcs_planner.mission.onboard_applet import applet_text, point_codes, report_value
from gcs_planner.mission.onboard_mission import onboard_mission
from gcs_planner.mission.policy_missions import PolicyMissions, Switch


@pytest.fixture(scope="module")
def policy() -> PolicyMissions:
    return policy_missions(policy_scenario())


def _applet(policy: PolicyMissions) -> str:
    return applet_text(onboard_mission(policy), point_codes(policy_scenario().ids), "test")


class FakeArduPilot:
    """The autopilot as the bindings see it, its nav index moved by the test."""

    def __init__(self, items: tuple[MissionItem, ...]) -> None:
        self.items = items
        self.state = MISSION_RUNNING
        self.index = 2
        self.texts: list[tuple[int, str]] = []

    def mission_state(self) -> int:
        return self.state

    def num_commands(self) -> int:
        return len(self.items)

    def get_item(self, index: int) -> MissionItem | None:
        return self.items[index] if 0 <= index < len(self.items) else None

    def current_nav_index(self) -> int:
        return self.index

    def set_current_cmd(self, index: int) -> bool:
        self.index = index
        return True

    def send_text(self, severity: int, text: str) -> None:
        self.texts.append((severity, text))

    def parameter(self, name: str) -> float | None:
        return None


def _host(policy: PolicyMissions, items=None):  # noqa: ANN001, ANN202 - a test helper
    vehicle = FakeArduPilot(items or onboard_mission(policy).mission.items)
    errors: list[str] = []
    host = ScriptHost(_applet(policy), vehicle, on_error=errors.append)
    host.run_due(0.0)
    return host, vehicle, errors


def test_the_onboard_mission_is_the_primary_then_the_branch_behind_its_end(policy) -> None:
    onboard = onboard_mission(policy)
    primary, branch = policy.missions["primary"], policy.missions["after-P2"]
    items = onboard.mission.items
    n = len(primary.items)
    assert [it.seq for it in items] == list(range(len(items)))
    assert [replace(it, seq=0) for it in items[:n]] == [replace(it, seq=0) for it in primary.items]
    assert items[n - 1].command == MAV_CMD_NAV_LOITER_UNLIM  # the primary's end holds it
    (s,) = onboard.switches
    assert (s.item, s.resume, s.late, s.jump) == (4, n, n + 1, True)
    own = branch.items[policy.switches[0].resume_item :]
    assert [replace(it, seq=0) for it in items[n:]] == [replace(it, seq=0) for it in own]
    assert onboard.index_of("after-P2", 5) == n and onboard.mission_at(n) == "after-P2"


def test_a_segment_that_ends_with_rtl_is_held_at_home_and_same_items_share_a_segment(
    policy,
) -> None:
    def rtl(mission):  # noqa: ANN001, ANN202
        items = (*mission.items[:-1], MissionItem(len(mission.items) - 1, 2, 20))
        return replace(mission, items=items, at_end="rtl")

    primary, branch = rtl(policy.missions["primary"]), rtl(policy.missions["after-P2"])
    same = Switch("after-P2", "V3", dict(branch.point_seqs)["V3"], "again", 7)
    rtl_policy = PolicyMissions(
        "primary",
        {"primary": primary, "after-P2": branch, "again": branch},
        (*policy.switches, same),
    )
    onboard = onboard_mission(rtl_policy)
    items = onboard.mission.items
    n = len(primary.items)
    assert items[n - 1].command == MAV_CMD_NAV_RETURN_TO_LAUNCH
    assert items[n].command == MAV_CMD_NAV_LOITER_UNLIM and items[-1].command == items[n].command
    assert onboard.switches[0].resume == n + 1  # the branch's items behind the hold
    again = onboard.switches[1]
    assert not again.jump and onboard.segments["again"] == onboard.segments["after-P2"]
    assert onboard.index_of("again", 7) == onboard.index_of("after-P2", 7)


def test_the_applet_is_deterministic_and_calls_only_documented_bindings(policy) -> None:
    text = _applet(policy)
    assert text == _applet(policy)
    # Every call on an ArduPilot object: obj:method( and the mission's fields; the applet's
    # local `item` is a mavlink_mission_item_int_t_ud (mission:get_item's result).
    calls = {
        f"{'mavlink_mission_item_int_t_ud' if obj == 'item' else obj}:{name}"
        for obj, name in re.findall(r"\b([A-Za-z_]\w*):([A-Za-z_]\w*)\(", text)
    }
    calls |= {f"mission.{f}" for f in re.findall(r"\bmission\.([A-Za-z_]\w*)", text)}
    assert calls, "the applet calls no binding"
    assert calls <= set(BINDINGS), calls - set(BINDINGS)
    assert set(onboard_applet.BINDINGS) <= set(BINDINGS)
    for binding in onboard_applet.BINDINGS:
        assert binding.split(":")[-1] in text  # each binding the header quotes is called


def test_a_failed_or_missed_fix_sets_the_branch_current_within_one_tick(policy) -> None:
    for outcome in ("FAILED", "MISSED"):
        host, vehicle, errors = _host(policy)
        host.run_due(100.0)
        vehicle.index = 4  # on the way to P2
        host.write_parameter("PLCY_FIX", report_value(3, outcome))
        host.run_due(150.0)
        assert vehicle.index == 4  # its next run is at 200 ms: the interval is honoured
        host.run_due(200.0)
        assert vehicle.index == 7 and host.jumps == [(200.0, 7)] and not errors
        assert any("P2" in text and "after-P2" in text for _, text in vehicle.texts)


def test_a_made_fix_keeps_the_primary_and_no_report_past_the_run_out_switches_late(
    policy,
) -> None:
    host, vehicle, _ = _host(policy)
    vehicle.index = 5
    host.write_parameter("PLCY_FIX", report_value(3, "made"))
    for t in range(100, 1100, 100):
        host.run_due(float(t))
    assert vehicle.index == 5 and not host.jumps
    host, vehicle, _ = _host(policy)
    vehicle.index = 5  # P2's item (4) and the next one reached with no report at all
    host.run_due(100.0)
    assert vehicle.index == 5
    vehicle.index = 6
    host.run_due(200.0)
    assert vehicle.index == 8  # the branch's item after its first: no turning back


def test_the_applet_stays_off_on_a_mission_that_is_not_the_policys(policy) -> None:
    items = onboard_mission(policy).mission.items
    other = (*items[:4], replace(items[4], x=items[4].x + 100), *items[5:])
    host, vehicle, _ = _host(policy, other)
    host.run_due(100.0)
    assert not host.running and any(sev == 2 for sev, _ in vehicle.texts)
    host, vehicle, _ = _host(policy)
    vehicle.state = MISSION_STOPPED  # on the ground: it waits
    host.write_parameter("PLCY_FIX", report_value(3, "FAILED"))
    host.run_due(100.0)
    assert host.running and vehicle.index == 2


def test_the_scripting_host_keeps_to_what_ardupilot_does(policy) -> None:
    vehicle = FakeArduPilot(onboard_mission(policy).mission.items)

    def stopped(text: str) -> str:
        errors: list[str] = []
        host = ScriptHost(text, vehicle, on_error=errors.append)
        host.run_due(0.0)
        host.run_due(10_000.0)
        assert not host.running
        return errors[0] if errors else ""

    assert "ahrs" in stopped("return ahrs:get_location()")  # not provided: an error, not nil
    assert "not provided" in stopped("local m = mission:get_item(1)\nreturn m:nonsense()")
    assert "Incorrect number of arguments" in stopped("mission:set_current_cmd()")
    assert "method" in stopped("mission.set_current_cmd(3)")
    assert "exceeded time limit" in stopped("while true do end")
    assert "bad result count" in stopped("return 1")
    assert "did not return a function" in stopped("return 1, 100")
    assert "Error" in stopped("x = = 1")
    assert stopped("return") == ""  # returned nothing: ended, no error
    host = ScriptHost(
        "local n = 0\nlocal function f()\n n = n + 1\n return f, 250\nend\nreturn f, 250",
        vehicle,
    )
    for t in range(0, 1001, 50):
        host.run_due(float(t))
    assert host.runs == 5  # at 0 (the chunk), then every 250 ms
