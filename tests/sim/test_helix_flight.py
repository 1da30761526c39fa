"""Helices (airplane legs too steep for their length) flown by the mock vehicle as each autopilot
flies the items the exporter writes for it: ArduPlane counts LOITER_TURNS, PX4 loiters to an
altitude and leaves on the heading to the target.

ArduPlane configured for the plan (TECS_CLMB_MAX / TECS_SINK_MAX at the plan's rates and
NAVL1_LIM_BANK at its roll limit, so that AP_L1_Control::loiter_radius keeps the planned radius
at altitude) flies each leg within tens of metres of its planned length and overflies every
correction point within the capture radius. With its shipped NAVL1_LIM_BANK = 0 it widens every
helix by EAS2TAS^2 and the legs come out kilometres long; PX4 switches to the next item at npfg's
switch distance and misses correction points the route turns at: both findings are tested here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from gcs_planner.sim.guidance import AutopilotParams
from gcs_planner.sim.replay import replay
from support.flights import DS2, DS2_LIMITS, configured
from support.missions import make_plan, steep_scenario

from gcs_planner.aircraft.autopilot import ARDUPLANE, PX4, autopilot_for
from gcs_planner.aircraft.profile import DEFAULT_CAPTURE_RADIUS_M
from gcs_planner.core.bnb import flown_route
from gcs_planner.core.planner import plan
from gcs_planner.geometry.airplane import airplane_leg
from gcs_planner.mission.builder import build_mission, px4_leaves_on_heading, route_legs
from gcs_planner.mission.plan_json import plan_to_dict
from gcs_planner.scenario.georef import LocalFrame
from gcs_planner.scenario.model import Kind, Scenario
from gcs_planner.scenario.readers import load_scenario

# Turn entry: the aircraft banks at most to its turning radius, so a turn it starts late is
# never caught up; a leg's arc is flown up to this much longer than planned (both autopilots).
LEG_OVERRUN_M = 60.0


def flown_against_planned(
    stops, items, scenario, flavour: str, autopilot: AutopilotParams | None = None
) -> list[tuple[str, int, float]]:
    """(point, helix turns, flown minus planned length of the leg to it) for each correction
    point of the route, after checking that the flight overflew it within the capture radius."""
    autopilot = autopilot or configured(scenario, flavour)
    report = replay(items, scenario, home_at_seq0=autopilot_for(flavour).home_at_seq0,
                    flavour=flavour, autopilot=autopilot)  # fmt: skip
    met = {e.id: e for e in report.encounters}
    out = []
    flown_before = planned_before = 0.0
    for stop in stops[1:-1]:
        assert stop.id in met, f"{flavour}: correction point {stop.id} missed"
        e = met[stop.id]
        assert e.miss <= DEFAULT_CAPTURE_RADIUS_M
        turns = int(getattr(stop.leg, "helix_turns", 0))
        over = (e.distance - flown_before) - (stop.cumulative - planned_before)
        out.append((stop.id, turns, over))
        flown_before, planned_before = e.distance, stop.cumulative
    return out


def test_helix_legs_are_flown_as_planned_on_a_small_steep_route():
    """Legs of 5 to 22 turns at 4/5 degree limits, from A (free heading) on: ArduPlane set up
    for the plan flies them as planned."""
    s = steep_scenario()
    points = [0, 1, 2, 3, 4, 5, 6]
    route = flown_route(s, tuple(points))
    m = build_mission(
        make_plan(s, routes=(points,), probability=False), firmware=ARDUPLANE.firmware
    )
    legs = flown_against_planned(route.stops, m.items, s, ARDUPLANE.firmware)
    assert sum(turns > 0 for _, turns, _ in legs) >= 4
    for pid, turns, over in legs:
        assert -LEG_OVERRUN_M < over < LEG_OVERRUN_M, f"leg to {pid} ({turns} turns)"


def test_arduplane_shipped_loiter_scaling_lengthens_the_helices_at_altitude():
    """The same route with ArduPlane's shipped NAVL1_LIM_BANK = 0: every helix radius is scaled
    by EAS2TAS^2 (AP_L1_Control::loiter_radius), so the helix legs come out kilometres long."""
    s = steep_scenario()
    points = [0, 1, 2, 3, 4, 5, 6]
    route = flown_route(s, tuple(points))
    m = build_mission(
        make_plan(s, routes=(points,), probability=False), firmware=ARDUPLANE.firmware
    )
    report = replay(m.items, s, home_at_seq0=True, flavour=ARDUPLANE.firmware,
                    autopilot=configured(s, ARDUPLANE.firmware, lim_bank=0.0))  # fmt: skip
    met = {e.id: e for e in report.encounters}
    first = route.stops[1]
    assert first.id in met and int(first.leg.helix_turns) > 0
    assert met[first.id].distance - first.cumulative > 1000.0


def test_px4_switch_distance_misses_the_correction_points_of_a_helix_route():
    """PX4 accepts each waypoint at npfg's switch distance (~57-70 m) and turns for the next
    item there: a correction point the route turns at is passed outside the 5 m capture
    radius (the planner must give PX4 straight run-ins and run-outs)."""
    s = steep_scenario()
    points = [0, 1, 2, 3, 4, 5, 6]
    route = flown_route(s, tuple(points))
    m = build_mission(make_plan(s, routes=(points,), probability=False), firmware=PX4.firmware)
    report = replay(m.items, s, home_at_seq0=False, flavour=PX4.firmware,
                    autopilot=configured(s, PX4.firmware))  # fmt: skip
    met = {e.id for e in report.encounters}
    assert not {stop.id for stop in route.stops[1:-1]} <= met


@pytest.fixture(scope="module")
def ds2_route(dataset_paths):
    scenario = load_scenario(dataset_paths[2], {**DS2, **DS2_LIMITS})
    p = plan(scenario, objectives=("length", "corrections", "probability"), choice="most-reliable")
    return scenario, p.route, plan_to_dict(p)


def test_dataset2_helix_legs_are_overflown_when_arduplane_climbs_at_the_true_airspeed(ds2_route):
    """The certain route of dataset 2 at 20/25 degrees: six legs with helices of 1 to 4 turns
    and points up to 10 km high, where 25 m/s EAS is 34 m/s true. Set to climb at the plan's
    angles at the top's true airspeed, ArduPlane overflies every correction point; its straight
    legs come out within tens of metres, its helices longer (it climbs steeper than planned low
    down, then circles level: measured 110 m for 1 turn, 323 m for 4, since the glide slope
    gives no climb feed-forward before its ramp starts), never more than about 120 m per turn.
    At the plan's rates as EAS angles it arrives low (next test)."""
    scenario, route, plan_dict = ds2_route
    flavour = ARDUPLANE.firmware
    m = build_mission(plan_dict, firmware=flavour, acceptance_radius=1)
    legs = flown_against_planned(route.stops, m.items, scenario, flavour)
    assert any(turns > 0 for _, turns, _ in legs)
    for pid, turns, over in legs:
        bound = LEG_OVERRUN_M if turns == 0 else 120.0 * turns
        assert -LEG_OVERRUN_M < over < bound, f"{flavour} leg to {pid} ({turns} turns)"


def test_dataset2_at_the_plans_rates_arrives_low_at_altitude(ds2_route):
    """TECS rates are vertical metres per second: the plan's 20 degrees at 25 m/s (8.6 m/s) is
    15 degrees through the air at 34 m/s true, so correction points high up are missed below."""
    scenario, _, plan_dict = ds2_route
    v = scenario.vehicle
    ap = AutopilotParams(ARDUPLANE.firmware, loiter_radius=v.turn_radius, acceptance_radius=1.0,
                         loiter_bank_limit=45.0).with_rates(v.climb_rate, v.sink_rate)  # fmt: skip
    m = build_mission(plan_dict, firmware=ARDUPLANE.firmware, acceptance_radius=1)
    report = replay(m.items, scenario, home_at_seq0=True, flavour=ARDUPLANE.firmware, autopilot=ap)
    assert not report.arrived and report.missed


@pytest.mark.parametrize(
    "end, leaves_on_heading",
    [((3000.0, 0.0, 1200.0), True), ((150.0, 10.0, 400.0), False), ((150.0, 10.0, -400.0), False)],
)
def test_px4_is_asked_for_the_exit_heading_only_where_it_enforces_it(end, leaves_on_heading):
    """PX4 enforces a loiter's exit heading only towards a waypoint farther than 1.2 radii from
    the centre: a target right beside the turning circle gets the helix-only loiter."""
    leg = airplane_leg(np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array(end), 200.0, 15.0, 15.0)
    assert leg.helix_turns > 0
    assert px4_leaves_on_heading(leg) is leaves_on_heading


def test_px4_helix_beside_its_target_is_written_as_waypoints():
    """A target right beside the turning circle: PX4 would leave a loiter wherever the altitude
    came in, so the helix goes as waypoints 16 degrees apart at the plan's altitudes."""
    s0 = steep_scenario()
    xyz = np.array([[0, 0, 0], [10000, 0, 500], [10150, 10, 900], [20000, 0, 1000]], float)
    kinds = np.array([Kind.A, Kind.V, Kind.H, Kind.B], dtype=np.uint8)
    s = Scenario(ids=("A0", "1", "2", "B9"), xyz=xyz, kind=kinds, unreliable=np.zeros(4, bool),
                 params=s0.params, name="beside", source="hand-made", origin=s0.origin)  # fmt: skip
    plan_dict = make_plan(s, routes=([0, 1, 2, 3],), probability=False)
    leg = route_legs(plan_dict["front"][0])[1]
    assert leg.helix_turns == 5 and not px4_leaves_on_heading(leg)
    m = build_mission(plan_dict, firmware=PX4.firmware)
    assert not [it for it in m.items if it.command in (18, 31)]
    helix = [it for it in m.items if it.note.startswith("helix 1->2")]
    assert len(helix) == math.ceil(5 * 360 / 16)
    frame = LocalFrame(s.origin)
    zs = [frame.to_local(it.lat, it.lon, it.z)[2] for it in helix]
    assert all(a < b for a, b in zip(zs, zs[1:]))  # climbing all the way
    x, y, _ = frame.to_local(helix[-1].lat, helix[-1].lon, helix[-1].z)
    assert math.hypot(x - 10000.0, y) < 0.05  # whole turns: above the correction point it left


def test_no_arduplane_arc_waypoint_lies_within_the_lap_counts_slack_after_a_helix(ds2_route):
    """ArduPlane leaves a loiter for a next waypoint on its circle the moment its count of turns
    is done; the count ends where the wind and the capture put it, so the first arc waypoint
    after each helix lies at least ARDUPLANE_LAP_SLACK_DEG past the helix's start (the end of
    the run-out, where the helix begins), or there is none and the target follows."""
    from gcs_planner.mission.builder import (
        ARDUPLANE_LAP_SLACK_DEG,
        MAV_CMD_NAV_LOITER_TURNS,
        route_entry,
    )

    _, _, plan_dict = ds2_route
    m = build_mission(plan_dict, firmware=ARDUPLANE.firmware, acceptance_radius=1)
    frame = LocalFrame(m.origin)
    legs = [leg for leg in route_legs(route_entry(plan_dict)[1]) if leg.helix_turns > 0]
    loiters = [k for k, it in enumerate(m.items) if it.command == MAV_CMD_NAV_LOITER_TURNS]
    assert len(loiters) == len(legs) > 0
    checked = 0
    for k, leg in zip(loiters, legs, strict=True):
        after = m.items[k + 1]
        if "arc" not in after.note:
            continue  # the target's own waypoint: ArduPlane leaves on the course to it
        p = np.array(frame.to_local(after.x / 1e7, after.y / 1e7, after.z))[:2]
        start = leg.point_at_horizontal(leg.run_out)[:2]
        c = np.asarray(leg.centre[:2])
        a0, a1 = np.arctan2(*(start - c)[::-1]), np.arctan2(*(p - c)[::-1])
        swept = abs(math.remainder(a1 - a0, 2 * math.pi))
        assert swept >= math.radians(ARDUPLANE_LAP_SLACK_DEG) - 1e-6, (after.note, swept)
        checked += 1
    assert checked > 0  # some helix is followed by the rest of its arc
