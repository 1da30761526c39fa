"""The ground-switched flight's two defects of the 400-run dry run (docs/flying-policies.md, "A
policy flown on dataset 2"), each flown over real UDP on 127.0.0.1 against the live mock
vehicle with exactly the messages that caused it dropped (no random loss):

* "the vehicle did not start the mission within 600 s": the ground station knew a flight only
  by an armed HEARTBEAT. The mock beats at 1 Hz of wall time and a dry-run flight in its time
  warp can start and end between two beats: when the one armed beat is lost, the ground station
  never sees the flight and waits for it until its start wait runs out. It now also knows a
  flight by an item reached or a correction report, and its end by a disarmed beat after that.
  A lost MISSION_START acknowledgement is not sent again once the vehicle is seen flying (a copy
  reaching a vehicle whose flight is over started the mission once more).
* run 59's item set current 14.3 km after a fix: a DO_SET_MISSION_CURRENT whose first copy was
  taken with its acknowledgement lost, and the next copy lost on the way, left a third copy as
  the honest time scale closed (two of the ground station's timeouts after the last copy taken):
  it landed at the cruise scale and turned the aircraft back to the item. The dry run now holds
  the honest scale for four of the ground station's timeouts (policies/dry_run.py).
"""

from __future__ import annotations

from typing import Any

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from support.policy_scenario import policy_missions, policy_scenario

from gcs_planner.errors import LinkError
from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.policies import dry_run as policy_dry_run_module
from gcs_planner.policies.flight import MAV_MODE_FLAG_SAFETY_ARMED, PolicyFlight

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

SET_CURRENT = mavlink.MAV_CMD_DO_SET_MISSION_CURRENT


class _Scripted(MockVehicle):
    """The mock vehicle with scripted drops: ``drop_armed`` loses every HEARTBEAT that says
    armed; ``drop_start_acks`` that many MISSION_START acknowledgements; ``drop_set_current_ack``
    the first DO_SET_MISSION_CURRENT acknowledgement; ``drop_set_current_copies`` the copies of
    DO_SET_MISSION_CURRENT (1 the first) lost on their way to the vehicle. It logs the items it
    reports reached."""

    made: list[_Scripted] = []

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.drop_armed = False
        self.drop_start_acks = 0
        self.drop_set_current_ack = False
        self.drop_set_current_copies: frozenset[int] = frozenset()
        self.set_current_copies = 0
        self.reached: list[int] = []
        super().__init__(*args, **kwargs)
        _Scripted.made.append(self)

    def _send(self, msg: Any) -> None:
        kind = msg.get_type()
        if kind == "HEARTBEAT" and self.drop_armed and msg.base_mode & MAV_MODE_FLAG_SAFETY_ARMED:
            return
        if kind == "COMMAND_ACK" and msg.command == mavlink.MAV_CMD_MISSION_START:
            if self.drop_start_acks > 0:
                self.drop_start_acks -= 1
                return
        if kind == "COMMAND_ACK" and msg.command == SET_CURRENT and self.drop_set_current_ack:
            self.drop_set_current_ack = False
            return
        if kind == "MISSION_ITEM_REACHED":
            self.reached.append(int(msg.seq))
        super()._send(msg)

    def _on_command_long(self, msg: Any, peer: Any) -> None:
        if msg.command == SET_CURRENT:
            self.set_current_copies += 1
            if self.set_current_copies in self.drop_set_current_copies:
                return
        super()._on_command_long(msg, peer)


def _fly_with(vehicle: _Scripted, policy: Any, timeout: float) -> Any:
    with vehicle:
        link = open_link(f"udpout:127.0.0.1:{vehicle.port}")
        try:
            client = MissionClient(link, timeout=timeout, retries=5, transfer="mission")
            client.connect(10.0)
            # A start wait far beyond the flight's: only a ground station that never sees the
            # flight reaches it.
            outcome = PolicyFlight(client, policy, say=lambda _line: None).run(
                start=True, start_wait=30.0
            )
        finally:
            link.close()
        vehicle._fly_thread.join(60.0)
    return outcome


def _vehicle(scenario: Any, **kw: Any) -> _Scripted:
    port = free_udp_port()
    vehicle = _Scripted(f"udpin:127.0.0.1:{port}", scenario=scenario, live=True,
                        navigate_on_estimate=False, **kw)  # fmt: skip
    vehicle.port = port
    return vehicle


def test_a_flight_whose_armed_heartbeats_are_all_lost_is_still_followed_to_its_end():
    # Every HEARTBEAT that says armed is lost (a whole flight between two 1 Hz beats, its one
    # armed beat lost): the flight is known by its reports and items reached, its end by the
    # disarmed beat after them. Before, the ground station waited out its start wait.
    scenario = policy_scenario(1.0)
    policy = policy_missions(scenario)
    vehicle = _vehicle(scenario, speedup=40.0)
    vehicle.drop_armed = True
    try:
        outcome = _fly_with(vehicle, policy, timeout=0.5)
    except LinkError as exc:
        pytest.fail(f"the ground station did not follow the flight: {exc}")
    assert outcome.ended == "landed" and outcome.missions_flown == ("primary",)
    assert [r.point for r in outcome.reports] == ["H1", "P2"]
    assert vehicle.last_live.arrived


def test_a_lost_start_acknowledgement_starts_no_second_flight():
    # The first MISSION_START's acknowledgement is lost; the vehicle is seen flying before the
    # ground station's timeout, so the command is not sent again (a copy reaching the vehicle
    # after its flight is over starts the mission once more: the mock, as both autopilots,
    # accepts MISSION_START while flying).
    scenario = policy_scenario(1.0)
    policy = policy_missions(scenario)
    vehicle = _vehicle(scenario, speedup=40.0)
    vehicle.drop_start_acks = 1
    outcome = _fly_with(vehicle, policy, timeout=3.0)
    starts = [c for c, _ in vehicle.commands if c == mavlink.MAV_CMD_MISSION_START]
    assert starts == [mavlink.MAV_CMD_MISSION_START]
    assert outcome.ended == "landed" and vehicle.last_live.arrived


def test_a_late_set_current_copy_lands_in_honest_time_and_turns_nothing_back(monkeypatch):
    # The dry run of the ground-switched policy (fix at P2 always fails) with the first set-current
    # taken and its acknowledgement lost, and the next two copies lost on their way: the fourth
    # leaves three ground-station timeouts after the first. With the honest scale held two
    # timeouts it landed at the cruise scale, after the aircraft had passed V3 (the item set),
    # and turned it back to V3, reached twice; held four, it lands before V3, where setting V3
    # again changes nothing.
    scenario = policy_scenario(0.0)
    policy = policy_missions(scenario)
    v3 = dict(policy.missions["after-P2"].point_seqs)["V3"]

    def scripted(*args: Any, **kwargs: Any) -> _Scripted:
        vehicle = _Scripted(*args, **kwargs)
        vehicle.drop_set_current_ack = True
        vehicle.drop_set_current_copies = frozenset({2, 3})
        return vehicle

    _Scripted.made = []
    monkeypatch.setattr(policy_dry_run_module, "MockVehicle", scripted)
    report = policy_dry_run_module.policy_dry_run(
        policy, scenario, runs=1, time_scale=10.0, cruise_scale=50.0, timeout=1.5,
        navigate_on_estimate=False,
    )  # fmt: skip
    (vehicle,) = _Scripted.made
    (run,) = report.runs
    assert vehicle.set_current_copies == 4  # the script ran: copies 2 and 3 lost, 4 taken
    assert vehicle.reached.count(v3) == 1, f"items reached: {vehicle.reached}"
    assert run.arrived and not run.link_failed, run.why
