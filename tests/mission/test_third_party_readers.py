"""Real third-party readers accept every mission file the project writes, with the right item
count and coordinates: MAVSDK's importers (native v4 binding) and pymavlink's MAVWPLoader.

MAVSDK's MissionRaw needs a System, which it creates when one HEARTBEAT arrives on a ``raw://``
connection: the HEARTBEAT is encoded with pymavlink and handed over as bytes (no vehicle, no
socket). The heartbeat's autopilot field decides how MAVSDK treats home:

* .plan: for ArduPilot MAVSDK inserts ``plannedHomePosition`` as item 0 (our seq 0); for PX4 it
  takes the items as they are.
* .waypoints: MAVSDK keeps row 0 (home) as an item, and for ArduPilot also inserts a copy of it
  in front, so it returns one item more than the file has rows.
"""

from __future__ import annotations

import pytest
from mavsdk import ComponentType, Configuration, Mavsdk
from mavsdk.plugins.mission_raw import MissionRaw
from pymavlink import mavwp
from pymavlink.dialects.v20 import common as mavlink2
from support.missions import HOME, make_plan, steep_scenario

from gcs_planner.mission.builder import build_mission
from gcs_planner.mission.items import MAV_FRAME_MISSION
from gcs_planner.mission.qgc_plan import write_plan
from gcs_planner.mission.waypoints import write_waypoints

AUTOPILOT = {
    "ardupilot": mavlink2.MAV_AUTOPILOT_ARDUPILOTMEGA,
    "px4": mavlink2.MAV_AUTOPILOT_PX4,
}
# The loiters a helix is written as (ArduPlane, PX4).
LOITERS = (mavlink2.MAV_CMD_NAV_LOITER_TURNS, mavlink2.MAV_CMD_NAV_LOITER_TO_ALT)
OPTIONS = [
    {
        "firmware": fw,
        "altitude_frame": fr,
        "at_end": end,
        "home": HOME if fr == "relative" else None,
    }
    for fw in ("ardupilot", "px4")
    for fr in ("amsl", "relative")
    for end in ("loiter", "rtl", "land")
]
# PX4 missions are not written as .waypoints (mission/waypoints.py;
# tests/mission/test_altitude_frames.py).
WAYPOINTS_OPTIONS = [o for o in OPTIONS if o["firmware"] == "ardupilot"]
# The plain tiny plan, and one whose climbs need helices (loiter items in the mission).
PLANS = {"flat": lambda: make_plan(), "helices": lambda: make_plan(steep_scenario())}


def option_id(opts: dict) -> str:
    return "-".join(v for v in opts.values() if isinstance(v, str))


@pytest.fixture(scope="module")
def mission_raw():
    """MissionRaw plugins on MAVSDK systems announced by one HEARTBEAT each, by firmware."""
    made = {}
    for sysid, (firmware, autopilot) in enumerate(AUTOPILOT.items(), start=1):
        sdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        assert sdk.add_any_connection("raw://") is not None
        encoder = mavlink2.MAVLink(None, srcSystem=sysid, srcComponent=1)
        heartbeat = encoder.heartbeat_encode(
            mavlink2.MAV_TYPE_FIXED_WING, autopilot, 0, 0, mavlink2.MAV_STATE_STANDBY
        )
        sdk.pass_received_raw_bytes(bytes(heartbeat.pack(encoder)))
        system = sdk.first_autopilot(5.0)
        assert system is not None, "MAVSDK made no System from the HEARTBEAT"
        made[firmware] = (sdk, MissionRaw(system))
    yield {fw: plugin for fw, (_, plugin) in made.items()}
    for sdk, plugin in made.values():
        plugin.destroy()
        sdk.destroy()


def assert_same(theirs, ours) -> None:
    """MAVSDK's items against ours: command, frame, params, degE7 positions, float32 altitude."""
    assert len(theirs) == len(ours)
    for t, o in zip(theirs, ours, strict=True):
        assert (t.command, t.autocontinue) == (o.command, o.autocontinue)
        assert (t.param1, t.param2, t.param3, t.param4) == pytest.approx(
            (o.param1, o.param2, o.param3, o.param4), abs=1e-4
        )
        if o.frame == MAV_FRAME_MISSION:
            assert t.frame == o.frame and (t.x, t.y) == (0, 0)
        else:
            assert abs(t.x - o.x) <= 1 and abs(t.y - o.y) <= 1
        assert t.z == pytest.approx(o.z, rel=1e-6, abs=1e-3)


@pytest.mark.parametrize("plan", PLANS)
@pytest.mark.parametrize("opts", OPTIONS, ids=option_id)
def test_mavsdk_imports_every_plan(tmp_path, mission_raw, opts, plan):
    m = build_mission(PLANS[plan](), **opts)
    assert any(it.command in LOITERS for it in m.items) == (plan == "helices")
    path = write_plan(m, tmp_path / "mission.plan")
    data = mission_raw[m.firmware].import_qgroundcontrol_mission(str(path))
    items = data.mission_items
    assert [it.seq for it in items] == list(range(len(m.items)))
    # ArduPilot: MAVSDK rebuilds seq 0 (home, MAV_FRAME_GLOBAL_INT) from plannedHomePosition.
    if m.firmware == "ardupilot":
        home = items[0]
        assert (home.x, home.y) == (m.items[0].x, m.items[0].y)
        assert home.z == pytest.approx(m.home[2], rel=1e-6)
        assert_same(items[1:], m.items[1:])
    else:
        assert_same(items, m.items)
    for it, ours in zip(items, m.items, strict=True):
        if ours.frame != MAV_FRAME_MISSION and ours.seq > 0:
            assert it.frame == ours.frame
    assert data.geofence_items == [] and data.rally_items == []


@pytest.mark.parametrize("plan", PLANS)
@pytest.mark.parametrize("opts", WAYPOINTS_OPTIONS, ids=option_id)
def test_mavsdk_imports_every_waypoints_file(tmp_path, mission_raw, opts, plan):
    m = build_mission(PLANS[plan](), **opts)
    assert any(it.command in LOITERS for it in m.items) == (plan == "helices")
    path = write_waypoints(m, tmp_path / "mission.waypoints")
    items = mission_raw[m.firmware].import_mission_planner_mission(str(path)).mission_items
    rows = len(path.read_text().splitlines()) - 1
    assert rows == len(m.items)
    assert len(items) == rows + 1  # MAVSDK's extra copy of home in front
    assert (items[0].x, items[0].y) == (items[1].x, items[1].y)
    assert_same(items[1:], m.items)
    assert [it.seq for it in items] == list(range(len(items)))


@pytest.mark.parametrize("plan", PLANS)
@pytest.mark.parametrize("opts", WAYPOINTS_OPTIONS, ids=option_id)
def test_pymavlink_loads_every_waypoints_file(tmp_path, opts, plan):
    m = build_mission(PLANS[plan](), **opts)
    assert any(it.command in LOITERS for it in m.items) == (plan == "helices")
    path = write_waypoints(m, tmp_path / "mission.waypoints")
    loader = mavwp.MAVWPLoader()
    count = loader.load(str(path))
    offset = 0  # ArduPilot: row k is seq k, row 0 home
    assert count == len(m.items) + offset
    home = loader.wp(0)
    assert (home.x, home.y) == pytest.approx(m.home[:2], abs=0.5e-7)
    for item in m.items:
        wp = loader.wp(item.seq + offset)
        assert (wp.seq, wp.command, wp.frame) == (item.seq + offset, item.command, item.frame)
        if item.frame != MAV_FRAME_MISSION:
            assert (wp.x, wp.y) == pytest.approx((item.lat, item.lon), abs=1e-9)
        assert wp.z == pytest.approx(item.z, abs=5e-7)
        assert wp.param2 == pytest.approx(item.param2) and wp.param3 == pytest.approx(item.param3)
