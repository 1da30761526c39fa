"""Room to switch missions (gcs_planner/core/switch_room.py): a policy keeps every run-out at
least the switch distance, so a branch set current some seconds after its failed fix is flown
as planned; without it the aircraft has turned after the primary and flies back.

The fork: the primary A H1 P B turns right at P, the branch P -> V3 turns left. The live mock
(sim/live_flight.py) flies the primary, P's fix fails, and the branch is stored and set current
at its resume item a given number of simulated seconds after the fix was told: no link, so no
wall clock in the verdict.
"""

from __future__ import annotations

import numpy as np
import pytest
from gcs_planner.sim.guidance import AutopilotParams
from gcs_planner.sim.live_flight import LiveFlight
from support.missions import make_plan

from gcs_planner.aircraft.profile import tas_from_eas
from gcs_planner.cli import main
from gcs_planner.core.bnb import flown_route
from gcs_planner.core.switch_room import (
    GROUND_SWITCH_TIME_S,
    switch_room,
    with_switch_room,
)
from gcs_planner.mission.builder import build_mission
from gcs_planner.scenario.generate import DATASET1
from gcs_planner.scenario.model import Kind, Origin, Scenario

IDS = ("A0", "H1", "P2", "V3", "B4")
XYZ = np.array([
    [0.0, 0.0, 1000.0],  # A
    [2000.0, 0.0, 1000.0],  # H1
    [4000.0, 0.0, 1000.0],  # P: unreliable V
    [5200.0, 1800.0, 1000.0],  # V3: the branch's, to the left
    [6500.0, -2500.0, 1000.0],  # B: the primary turns right at P
])  # fmt: skip
PRIMARY, BRANCH = [0, 1, 2, 4], [0, 1, 2, 3, 4]
R = 150.0


def fork(departure: float = 0.0) -> Scenario:
    params = {**DATASET1.to_dict(), "alpha1": 35.0, "alpha2": 25.0, "beta1": 25.0,
              "beta2": 25.0, "theta": 38.0, "delta": 0.005, "fail_residual": 20.0,
              "p_success": 0.0, "turn_radius": R, "departure": departure}  # fmt: skip
    return Scenario(
        ids=IDS, xyz=XYZ.copy(),
        kind=np.array([Kind.A, Kind.H, Kind.V, Kind.V, Kind.B], dtype=np.uint8),
        unreliable=np.array([False, False, True, False, False]),
        params=DATASET1.__class__(**params), name="fork", source="hand-made",
        origin=Origin(lat=31.2, lon=122.8, alt=12.5),
    )  # fmt: skip


def test_the_room_is_the_capture_radius_and_the_switch_time_at_ground_speed() -> None:
    s = fork()
    room = switch_room(s, GROUND_SWITCH_TIME_S)
    tas = tas_from_eas(s.cruise_airspeed, 1000.0 + 12.5)
    assert room.ground_speed == pytest.approx(tas)
    assert room.distance == pytest.approx(s.capture_radius + GROUND_SWITCH_TIME_S * tas)
    assert with_switch_room(s, room).params.departure == pytest.approx(room.distance)
    # A longer run-out of the envelope's own is kept; straight legs have none to lengthen.
    longer = fork(departure=room.distance + 50.0)
    assert with_switch_room(longer, switch_room(longer, 10.0)) is longer
    straight = s.with_params(turn_radius=0.0)
    assert with_switch_room(straight, switch_room(straight, 10.0)) is straight
    with pytest.raises(ValueError):
        switch_room(s, -1.0)


def _switch_late(s: Scenario, delay: float) -> tuple[float, LiveFlight]:
    """Fly the primary until ``delay`` s after P's failed fix is told, then switch to the
    branch at its resume item; the distance flown from A to V3's fix, and the flight."""
    plan = make_plan(s, routes=(PRIMARY, BRANCH), probability=True)
    primary = build_mission(plan, route_index=0, firmware="ardupilot", acceptance_radius=1)
    branch = build_mission(plan, route_index=1, firmware="ardupilot", acceptance_radius=1)
    flight = LiveFlight(primary.items, s, flavour="ardupilot", profile=s.vehicle,
                        autopilot=AutopilotParams("ardupilot", loiter_radius=R),
                        capture_radius=5.0, rng=np.random.default_rng(1),
                        navigate_on_estimate=False)  # fmt: skip
    t, told = 0.0, None
    while flight.going and t < 1000.0:
        t += 0.5
        happened = flight.fly_until(t)
        if told is None and any(c.id == "P2" and c.succeeded is False
                                for c in happened.corrections):  # fmt: skip
            told = t
        if told is not None and t >= told + delay:
            break
    assert told is not None, "P's fix did not fail"
    flight.stored_changed(branch.items, keep_active=True)
    assert flight.set_current(branch.seq_of("P2") + 1)  # the resume item: the run-out's end
    while flight.going and t < 3000.0:
        t += 5.0
        flight.fly_until(t)
    v3 = [c.distance for c in flight.ins.corrections if c.id == "V3"]
    assert len(v3) == 1, "V3 not overflown"
    return v3[0], flight


@pytest.mark.parametrize("delay", [0.0, 4.0, 8.0])
def test_a_switch_within_the_room_flies_the_branch_as_planned(delay: float) -> None:
    s = fork()
    s = with_switch_room(s, switch_room(s, GROUND_SWITCH_TIME_S))
    planned = flown_route(s, tuple(BRANCH)).stops[3].cumulative
    flown, flight = _switch_late(s, delay)
    assert flown == pytest.approx(planned, abs=40.0)
    [(point, metres)] = flight.switches
    speed = switch_room(s, 0.0).ground_speed
    assert point == "P2" and delay * speed <= metres <= delay * speed + 40.0


def test_a_late_switch_without_room_flies_back_past_the_plan() -> None:
    s = fork()
    planned = flown_route(s, tuple(BRANCH)).stops[3].cumulative
    on_time, _ = _switch_late(s, 0.0)
    late, _ = _switch_late(s, 8.0)
    assert on_time == pytest.approx(planned, abs=40.0)
    assert late > planned + 400.0  # more than twice the reserve's default 200 m


def test_plan_policy_states_its_switch_room(tmp_path, capsys) -> None:
    """plan --policy writes the room into policy.json and the summary, and each branch resumes
    at the departure waypoint the room's run-out ends at; --switch-time is checked."""
    import json
    import math

    from support.policy_scenario import write_scenario

    from gcs_planner.mission.policy_file import read_policy

    toml = write_scenario(tmp_path, p_success=0.5)
    text = toml.read_text().replace("turn_radius = 0.0", f"turn_radius = {R}")
    toml.write_text(text)
    out = tmp_path / "out"
    rc = main(["plan", str(toml), "--choose", "shortest", "--min-probability", "0", "--out",
               str(out), "--policy", "--switch-time", "6"])  # fmt: skip
    said = capsys.readouterr().out
    assert rc == 0 and "switch room: every run-out >=" in said
    data = json.loads((out / "policy.json").read_text())
    room = data["switch_room"]
    assert room["switch_time_s"] == 6.0 and room["departure_m"] >= room["distance_m"] > 150.0
    plan = json.loads((out / "plan.json").read_text())
    assert plan["parameters"]["departure"] == pytest.approx(room["departure_m"])
    policy = read_policy(out / "policy.json")
    assert policy.switches
    for sw in policy.switches:
        items = policy.missions[sw.to_mission].items
        at, resume = items[sw.item], items[sw.resume_item]
        # the failed point's waypoint and the run-out's end (the shared departure waypoint)
        dy = (resume.lat - at.lat) * 111_320.0
        dx = (resume.lon - at.lon) * 111_320.0 * math.cos(math.radians(at.lat))
        assert math.hypot(dx, dy) == pytest.approx(room["departure_m"], abs=2.0)
        assert policy.missions[sw.mission].items[sw.resume_item] == resume
    capsys.readouterr()
    rc = main(["plan", str(toml), "--out", str(out), "--switch-time", "5"])
    assert rc == 2 and "--switch-time" in capsys.readouterr().err
    rc = main(["plan", str(toml), "--out", str(out), "--policy", "--switch-time", "-3"])
    assert rc == 2 and "--switch-time" in capsys.readouterr().err
