"""Route -> mission items: home, frames, correction waypoints, arc densification, end action.

``make_plan`` (support/missions.py) builds plan dicts (docs/plan-json.md) from small hand-made
scenarios through the project's own plan_json, so that the exporter is tested on the real
contract.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from support.missions import (
    GEOD,
    HOME,
    ORIGIN,
    geodesic_distance,
    make_plan,
    steep_scenario,
    tiny_scenario,
    true_position,
)

from gcs_planner.aircraft.autopilot import effective
from gcs_planner.errors import InputError
from gcs_planner.geometry.dubins import cs_leg
from gcs_planner.mission.builder import (
    DEFAULT_ACCEPTANCE_RADIUS,
    DEFAULT_CRUISE_SPEED,
    Mission,
    arc_step,
    arc_waypoints,
    build_mission,
    route_entry,
    route_legs,
)
from gcs_planner.mission.items import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TO_ALT,
    MAV_CMD_NAV_LOITER_TURNS,
    MAV_CMD_NAV_LOITER_UNLIM,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
)
from gcs_planner.scenario.georef import DEFAULT_ORIGIN, LocalFrame
from gcs_planner.scenario.model import Origin

# The loiters a helix is written as (ArduPlane, PX4).
HELICES = (MAV_CMD_NAV_LOITER_TURNS, MAV_CMD_NAV_LOITER_TO_ALT)


def nav(mission: Mission) -> list:
    return [it for it in mission.items if it.command == MAV_CMD_NAV_WAYPOINT]


# ---------------------------------------------------------------------------------------------


def test_ardupilot_mission_layout():
    plan = make_plan()
    m = build_mission(plan)
    route = plan["front"][0]["route"]
    assert m.firmware == "ardupilot" and m.route == tuple(route)
    home = m.items[0]
    assert home.seq == 0 and home.command == MAV_CMD_NAV_WAYPOINT and home.frame == MAV_FRAME_GLOBAL
    assert m.items[1].command == MAV_CMD_DO_CHANGE_SPEED
    assert m.items[1].param2 == DEFAULT_CRUISE_SPEED and m.cruise_speed == DEFAULT_CRUISE_SPEED
    assert [it.seq for it in m.items] == list(range(len(m.items)))
    # The route's points come in order, each on a waypoint with the capture radius.
    seqs = [m.seq_of(pid) for pid in route]
    assert seqs == sorted(seqs) and seqs[0] == 2
    for pid in route[1:]:
        it = m.items[m.seq_of(pid)]
        assert it.command == MAV_CMD_NAV_WAYPOINT
        assert it.param2 == DEFAULT_ACCEPTANCE_RADIUS and it.param3 == 0.0
        assert it.param2 == int(it.param2)
    assert m.items[-1].command == MAV_CMD_NAV_LOITER_UNLIM
    assert m.loiter_param == ("WP_LOITER_RAD", 200.0)
    # Home is A, in lat/lon/alt AMSL.
    a = plan["points"][0]
    lat, lon, alt = true_position(ORIGIN, a["x"], a["y"], a["z"])
    assert geodesic_distance(home.lat, home.lon, lat, lon) < 0.02
    assert home.z == pytest.approx(alt, abs=1e-9) and m.home[2] == pytest.approx(alt, abs=1e-9)


def test_px4_has_no_home_and_every_seq_shifts_by_one():
    """PX4's mission is ArduPlane's without the home item, every seq one lower, and for a plan
    with no run-out one waypoint more: straight on beyond B before the end action (next test)."""
    plan = make_plan()
    ap = build_mission(plan, firmware="ardupilot")
    px4 = build_mission(plan, firmware="px4")
    assert len(px4.items) == len(ap.items)
    assert px4.items[0].command == MAV_CMD_DO_CHANGE_SPEED
    b_seq = px4.seq_of(plan["front"][0]["route"][-1])
    beyond, end = px4.items[b_seq + 1], px4.items[b_seq + 2]
    assert beyond.command == MAV_CMD_NAV_WAYPOINT and beyond.note.startswith("departure")
    assert (end.command, end.x, end.y, end.z) == (
        ap.items[-1].command, ap.items[-1].x, ap.items[-1].y, ap.items[-1].z
    )  # fmt: skip
    for a, b in zip(ap.items[1 : b_seq + 2], px4.items[: b_seq + 1], strict=True):
        assert b.seq == a.seq - 1
        assert (a.command, a.frame, a.x, a.y, a.z, a.param2, a.param3) == (
            b.command,
            b.frame,
            b.x,
            b.y,
            b.z,
            b.param2,
            b.param3,
        )
    for pid in plan["front"][0]["route"]:
        assert px4.seq_of(pid) == ap.seq_of(pid) - 1
    assert px4.loiter_param == ("NAV_LOITER_RAD", 200.0)


def test_px4_flies_straight_on_beyond_b_when_the_plan_has_no_run_out():
    """PX4 switches to the end action npfg's switch distance before B (Navigator::
    get_acceptance_radius): the exporter continues the last leg beyond B, on its arrival
    heading at B's altitude, for npfg's settle distance at B's true airspeed (the run-out a
    derived plan keeps at every landmark). A plan with its own run-out keeps it."""
    from gcs_planner.aircraft.autopilot import effective
    from gcs_planner.aircraft.profile import tas_from_eas

    plan = make_plan()
    assert plan["parameters"]["departure"] == 0
    px4 = build_mission(plan, firmware="px4")
    frame = LocalFrame(px4.origin)
    b_seq = px4.seq_of(plan["front"][0]["route"][-1])
    b, beyond = px4.items[b_seq], px4.items[b_seq + 1]
    bx, by, bz = frame.to_local(b.x / 1e7, b.y / 1e7, b.z)
    ox, oy, oz = frame.to_local(beyond.x / 1e7, beyond.y / 1e7, beyond.z)
    eas = px4.cruise_speed  # the plan's cruise airspeed (EAS)
    want = effective("px4", {}).settle_distance(tas_from_eas(eas, b.z))
    assert math.hypot(ox - bx, oy - by) == pytest.approx(want, abs=0.05)
    assert oz == pytest.approx(bz, abs=1e-6)
    last = route_legs(route_entry(plan)[1])[-1]
    heading = math.atan2(oy - by, ox - bx)
    assert heading == pytest.approx(math.atan2(last.heading_out[1], last.heading_out[0]), abs=1e-4)
    # ArduPlane accepts B at the item's radius: no run-out added for it
    ap = build_mission(plan, firmware="ardupilot")
    assert not any(it.note.startswith("departure") for it in ap.items)


def test_correction_waypoints_are_on_the_true_wgs84_positions():
    """Every route point's waypoint within 0.05 m of its WGS84 position computed independently
    (geodesic from the origin), altitudes exact, in both frames; points up to 110 km away."""
    plan = make_plan()
    table = {p["id"]: p for p in plan["points"]}
    for frame_name in ("amsl", "relative"):
        m = build_mission(plan, altitude_frame=frame_name, home=HOME)
        home_alt = m.home[2]
        for pid in m.route:
            it = m.items[m.seq_of(pid)]
            p = table[pid]
            lat, lon, alt = true_position(ORIGIN, p["x"], p["y"], p["z"])
            assert geodesic_distance(it.lat, it.lon, lat, lon) < 0.05
            expected = alt if frame_name == "amsl" else alt - home_alt
            assert it.z == pytest.approx(expected, abs=1e-9)
            want = MAV_FRAME_GLOBAL if frame_name == "amsl" else MAV_FRAME_GLOBAL_RELATIVE_ALT
            assert it.frame == want
    far = max(math.hypot(p["x"], p["y"]) for p in plan["points"])
    assert far > 100_000


def test_relative_frame_altitudes_are_above_home():
    plan = make_plan()
    amsl = build_mission(plan)
    rel = build_mission(plan, altitude_frame="relative", home=HOME)
    assert rel.items[0].frame == MAV_FRAME_GLOBAL  # home always AMSL
    assert rel.home == (HOME.lat, HOME.lon, HOME.alt)
    for a, r in zip(amsl.items[2:], rel.items[2:], strict=True):
        if a.frame == MAV_FRAME_GLOBAL:
            assert r.frame == MAV_FRAME_GLOBAL_RELATIVE_ALT
            assert r.z == pytest.approx(a.z - HOME.alt, abs=1e-9)
    # A is in the air: its altitude above the stated home, not 0.
    assert rel.items[rel.seq_of("A0")].z == pytest.approx(amsl.home[2] - HOME.alt, abs=1e-9)


def test_arcs_are_densified_within_16_degrees_and_2_m_of_the_planned_arc():
    plan = make_plan()
    m = build_mission(plan)
    front = plan["front"][0]
    frame_origin = m.origin
    arc_items = [it for it in m.items if it.note.startswith("arc ")]
    turning = [leg for leg in front["legs"] if leg["geometry"]["arc"] is not None]
    assert turning and arc_items
    for leg in front["legs"]:
        g = leg["geometry"]
        own = [it for it in arc_items if it.note.startswith(f"arc {leg['from']}->{leg['to']} ")]
        if g["arc"] is None:
            assert not own  # straight legs need no intermediate item
            continue
        angle, radius = g["arc"]["angle"], g["radius"]
        # Consecutive points (start, arc points, tangent point) at most 16 degrees apart.
        n_steps = len(own) + (0 if g["straight_length"] >= 1.0 else 1)
        assert angle / n_steps <= math.radians(16.0) + 1e-12
        assert radius * (1 - math.cos(angle / n_steps / 2)) <= 2.0
        # Each arc item lies on the planned circle (within the file's 1e-7 degree rounding).
        c = np.array(g["arc"]["centre"])
        for it in own:
            lat, lon = it.lat, it.lon
            fwd_az, _, dist = GEOD.inv(frame_origin.lon, frame_origin.lat, lon, lat)
            x = dist * math.sin(math.radians(fwd_az))
            y = dist * math.cos(math.radians(fwd_az))
            z = it.z - frame_origin.alt
            off = np.array([x, y, z]) - c
            if g["model"] == "airplane":  # a horizontal circle, climbing at the leg's angle
                off[2] = 0.0
            assert abs(np.linalg.norm(off) - radius) < 0.05
            assert it.param2 >= 1 and it.param2 == int(it.param2)


@settings(max_examples=60, deadline=None)
@given(
    radius=st.floats(min_value=20.0, max_value=5_000.0),
    bearing=st.floats(min_value=-math.pi, max_value=math.pi),
    dist=st.floats(min_value=0.1, max_value=20.0),
)
def test_arc_points_stay_within_2_m_and_16_degrees(radius, bearing, dist):
    start = np.zeros(3)
    end = dist * radius * np.array([math.cos(bearing), math.sin(bearing), 0.1])
    leg = cs_leg(start, np.array([1.0, 0.0, 0.0]), end, radius)
    if not leg.reachable or leg.centre is None:
        return
    pts = arc_waypoints(leg)
    step = arc_step(radius)
    assert step <= math.radians(16.0)
    assert radius * (1 - math.cos(step / 2)) <= 2.0 + 1e-9
    chain = np.vstack([leg.start, pts])
    assert np.allclose(chain[-1], leg.tangent_point)
    # Every point on the circle, and each chord's mid-arc within 2 m of the chord.
    centre = np.asarray(leg.centre)
    assert np.allclose(np.linalg.norm(chain - centre, axis=1), radius, atol=1e-6 * radius)
    for p, q in zip(chain[:-1], chain[1:], strict=True):
        chord = np.linalg.norm(q - p)
        assert chord <= 2 * radius * math.sin(math.radians(8.0)) + 1e-6
        sagitta = radius - math.sqrt(max(radius**2 - (chord / 2) ** 2, 0.0))
        assert sagitta <= 2.0 + 1e-6


def test_loiter_radius_signed_by_the_last_turn():
    plan = make_plan()
    m = build_mission(plan)
    last_turn = next(
        leg["geometry"]["arc"]["sense"]
        for leg in reversed(plan["front"][0]["legs"])
        if leg["geometry"]["arc"] is not None and leg["geometry"]["arc"]["sense"] != 0
    )
    loiter = m.items[-1]
    assert abs(loiter.param3) == 200.0
    # MAVLink: positive = clockwise; the plan's sense +1 = counter-clockwise.
    assert (loiter.param3 > 0) == (last_turn == -1)
    assert (loiter.x, loiter.y, loiter.z) == (
        m.items[m.seq_of("B9")].x,
        m.items[m.seq_of("B9")].y,
        m.items[m.seq_of("B9")].z,
    )


def test_end_actions():
    plan = make_plan()
    rtl = build_mission(plan, at_end="rtl")
    assert rtl.items[-1].command == MAV_CMD_NAV_RETURN_TO_LAUNCH
    land = build_mission(plan, at_end="land", altitude_frame="relative", home=HOME)
    assert land.items[-1].command == MAV_CMD_NAV_LAND
    assert land.items[-1].z == pytest.approx(-land.home[2])  # sea level, relative to home
    b = land.items[land.seq_of("B9")]
    assert (land.items[-1].x, land.items[-1].y) == (b.x, b.y)


def test_other_front_routes_and_straight_plans():
    plan = make_plan(chosen=1)
    m = build_mission(plan)
    assert m.route == tuple(plan["front"][1]["route"]) and m.route_index == 1
    m2 = build_mission(plan, route_index=2)
    assert m2.route == ("A0", "B9")
    straight = make_plan(tiny_scenario(turn_radius=0.0))
    s = build_mission(straight)
    assert not [it for it in s.items if it.note.startswith("arc ")]
    assert s.loiter_param is None and s.items[-1].param3 == 0.0
    assert len(nav(s)) == 1 + len(straight["front"][0]["route"])  # home + route points


def test_origin_resolution():
    plan = make_plan()
    assert build_mission(plan).origin == ORIGIN and not build_mission(plan).origin_is_default
    other = Origin(-33.9, 151.3, 0.0)
    m = build_mission(plan, origin=other)
    assert m.origin == other and not m.origin_is_default
    bare = make_plan(tiny_scenario(origin=None))
    d = build_mission(bare)
    assert d.origin == DEFAULT_ORIGIN and d.origin_is_default


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"firmware": "inav"}, "firmware"),
        ({"altitude_frame": "terrain"}, "altitude-frame"),
        ({"at_end": "crash"}, "at-end"),
        ({"acceptance_radius": 12.5}, "acceptance-radius"),
        ({"acceptance_radius": 0}, "acceptance-radius"),
        ({"cruise_speed": -3}, "cruise-speed"),
        ({"cruise_speed": float("nan")}, "cruise-speed"),
        ({"route_index": 3}, "--route-index"),
        ({"origin": Origin(91.0, 0.0)}, "--origin"),
        ({"origin": Origin(float("nan"), 0.0)}, "--origin"),
    ],
)
def test_bad_options_are_input_errors(kwargs, field):
    with pytest.raises(InputError) as err:
        build_mission(make_plan(), **kwargs)
    assert err.value.field == field


@pytest.mark.parametrize(
    "mutate",
    [
        lambda p: p.update(format="something"),
        lambda p: p.update(version=7),
        lambda p: p.update(front=[]),
        lambda p: p["front"][0]["legs"].pop(),
        lambda p: p["front"][0]["legs"][1]["geometry"].pop("start"),
        lambda p: p["scenario"].update(origin={"lat": 95.0, "lon": 0.0}),
        lambda p: p["points"][1].update(x="east"),
        lambda p: p["parameters"].update(turn_radius="wide"),
        lambda p: p.update(chosen=True),
    ],
)
def test_bad_plans_are_input_errors(mutate):
    plan = make_plan()
    mutate(plan)
    with pytest.raises(InputError):
        build_mission(plan, source="plan.json")


@pytest.mark.parametrize("firmware", ["ardupilot", "px4"])
def test_helices_become_loiters_at_the_turning_radius_where_the_plan_climbs(firmware):
    """Each helix of an airplane leg is one loiter on its turning circle: centre R from the
    correction point it starts at, radius R signed by the turn's sense. ArduPilot counts the turns
    to the altitude the plan reaches at the end of the helix; PX4, which counts no turns, loiters
    helix and arc to the altitude of the arc's end and must leave on the heading to the target."""
    s = steep_scenario()
    plan = make_plan(s, routes=([0, 1, 2, 3, 4, 6],), probability=False)
    m = build_mission(plan, firmware=firmware)
    entry = plan["front"][0]
    helix_legs = [leg for leg in entry["legs"] if leg["helix_turns"] > 0]
    assert helix_legs, "the steep scenario must need helices"
    loiters = [it for it in m.items if it.command in HELICES]
    assert len(loiters) == len(helix_legs)
    frame = LocalFrame(ORIGIN)
    for leg, item in zip(helix_legs, loiters):
        geo = leg["geometry"]
        want = MAV_CMD_NAV_LOITER_TURNS if firmware == "ardupilot" else MAV_CMD_NAV_LOITER_TO_ALT
        assert item.command == want
        radius_param = item.param3 if firmware == "ardupilot" else item.param2
        assert abs(radius_param) == pytest.approx(200.0)
        # positive = clockwise (MAVLink): the opposite of our counter-clockwise sense
        assert math.copysign(1, radius_param) == -geo["arc"]["sense"]
        if firmware == "ardupilot":
            assert item.param1 == leg["helix_turns"]
            # heading required: leave on the tangent exit once the turns are done (common.xml)
            assert item.param2 == 1
        assert item.param4 == 1  # leave on the tangent, towards the next item
        x, y, z = frame.to_local(item.lat, item.lon, item.z)
        start = np.array(geo["start"])
        assert math.hypot(x - start[0], y - start[1]) == pytest.approx(200.0, abs=0.01)
        if firmware == "ardupilot":
            flat = geo["helix_length"] * math.cos(math.radians(leg["path_angle_deg"]))
            climb = flat * math.tan(math.radians(leg["path_angle_deg"]))
            assert z == pytest.approx(start[2] + climb, abs=0.01)
        else:
            assert item.param1 == 1  # heading required: it leaves where the tangent starts
            assert z == pytest.approx(geo["tangent_point"][2], abs=0.01)
            # the loiter flies the arc too: the next item is the target's waypoint
            target = m.items[item.seq + 1]
            assert target.command == MAV_CMD_NAV_WAYPOINT
            assert target.note.startswith(("correction", "B"))
    # every leg of the route is within the climb limits
    assert all(-5.0 - 1e-9 <= leg["path_angle_deg"] <= 4.0 + 1e-9 for leg in entry["legs"])
    # the correction points are still waypoints exactly on the landmarks
    for pid, seq in m.point_seqs:
        x, y, z = frame.to_local(m.items[seq].lat, m.items[seq].lon, m.items[seq].z)
        assert np.allclose([x, y, z], s.xyz[s.index_of(pid)], atol=0.01)


def test_loiter_turns_leave_on_the_tangent_in_the_exported_files():
    """NAV_LOITER_TURNS param2 = 1 ("heading required", common.xml) survives into the
    .waypoints rows and the QGroundControl .plan items the user flies."""
    from gcs_planner.mission.qgc_plan import plan_document
    from gcs_planner.mission.waypoints import dumps_waypoints, loads_waypoints

    plan = make_plan(steep_scenario(), routes=([0, 1, 2, 3, 4, 6],), probability=False)
    m = build_mission(plan, firmware="ardupilot")
    back = loads_waypoints(dumps_waypoints(m)).items
    turns = [it for it in back if it.command == MAV_CMD_NAV_LOITER_TURNS]
    assert turns and all(it.param2 == 1 for it in turns)
    doc = plan_document(m)
    items = [i for i in doc["mission"]["items"] if i.get("command") == MAV_CMD_NAV_LOITER_TURNS]
    assert items and all(i["params"][1] == 1 for i in items)


def test_px4_run_out_beyond_b_counts_the_design_wind_and_refuses_a_bad_one():
    """The run-out is the settle distance at B's TAS plus the plan's design wind (a plan whose
    envelope was derived for a wind); a design wind that is not a speed is refused, named."""
    plan = make_plan()

    def run_out(p: dict) -> float:
        m = build_mission(p, firmware="px4")
        frame = LocalFrame(m.origin)
        k = m.seq_of(p["front"][0]["route"][-1])
        b, beyond = (frame.to_local(it.x / 1e7, it.y / 1e7, it.z) for it in m.items[k : k + 2])
        return math.hypot(beyond[0] - b[0], beyond[1] - b[1])

    still = run_out(plan)
    windy = run_out({**plan, "vehicle": {"envelope": {"design_wind": 10.0}}})
    per_ms = effective("px4", {}).settle_distance(1.0)
    assert windy - still == pytest.approx(10.0 * per_ms, abs=0.1)
    for bad in ("ten", -1.0, float("nan")):
        with pytest.raises(InputError, match="design_wind"):
            build_mission({**plan, "vehicle": {"envelope": {"design_wind": bad}}}, firmware="px4")
