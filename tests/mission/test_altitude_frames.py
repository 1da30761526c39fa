"""Altitude frames and home (issue 29): relative altitudes only against a stated home, the home
written where the files carry it, and no PX4 .waypoints (its readers disagree on row 0)."""

from __future__ import annotations

import json

import pytest
from pymavlink import mavwp
from support.missions import HOME, make_plan

from gcs_planner.cli import main
from gcs_planner.errors import InputError
from gcs_planner.mission.builder import build_mission
from gcs_planner.mission.items import MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_RELATIVE_ALT
from gcs_planner.mission.qgc_plan import read_plan
from gcs_planner.mission.waypoints import loads_waypoints, write_waypoints


@pytest.fixture
def plan_file(tmp_path):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps({**make_plan(), "min_probability": 0.0}))
    return path


def test_relative_altitudes_without_a_home_are_refused(plan_file, tmp_path, capsys):
    out = tmp_path / "m.plan"
    args = ["export", str(plan_file), "--format", "plan", "--altitude-frame", "relative"]
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--home" in err and "\n" not in err and "Traceback" not in err
    assert not out.exists()
    with pytest.raises(InputError, match="stated home"):
        build_mission(make_plan(), altitude_frame="relative")


@pytest.mark.parametrize("text", ["31.2,122.8", "31.2,122.8,x", "95,122.8,0", "31,122,nan"])
def test_a_bad_home_is_one_line(plan_file, tmp_path, capsys, text):
    out = str(tmp_path / "m.plan")
    assert main(["export", str(plan_file), "--format", "plan", "--home", text, "--out", out]) == 2
    err = capsys.readouterr().err.strip()
    assert "'--home'" in err and "\n" not in err


def test_relative_altitudes_are_above_the_stated_home_in_every_file(plan_file, tmp_path):
    amsl = build_mission(make_plan())
    rel = build_mission(make_plan(), altitude_frame="relative", home=HOME)
    a_alt = amsl.home[2]  # without --home the home is A, in the air
    assert a_alt > HOME.alt
    assert rel.items[rel.seq_of("A0")].z == pytest.approx(a_alt - HOME.alt)
    for a, r in zip(amsl.items, rel.items, strict=True):
        if a.frame == MAV_FRAME_GLOBAL and a.seq > 0:
            assert r.frame == MAV_FRAME_GLOBAL_RELATIVE_ALT
            assert r.z + HOME.alt == pytest.approx(a.z)  # the same AMSL altitude
    out = tmp_path / "m.plan"
    args = ["export", str(plan_file), "--format", "plan", "--out", str(out)]
    assert main([*args, "--altitude-frame", "relative", "--home", "31.19,122.79,4"]) == 0
    doc = json.loads(out.read_text())
    assert doc["mission"]["plannedHomePosition"] == [31.19, 122.79, 4.0]
    assert read_plan(out).home == (31.19, 122.79, 4.0)


def test_pymavlink_reads_the_stated_home_as_row_0_and_the_items_after_it(tmp_path):
    """ArduPilot .waypoints: row 0 is home and seq 0, for QGroundControl, pymavlink's
    MAVWPLoader (which MAVProxy's `wp load` uploads row by row) and our reader alike."""
    m = build_mission(make_plan(), altitude_frame="relative", home=HOME)
    path = write_waypoints(m, tmp_path / "m.waypoints")
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(path)) == len(m.items)
    home = loader.wp(0)
    assert (home.x, home.y, home.z, home.frame) == pytest.approx(
        (HOME.lat, HOME.lon, HOME.alt, MAV_FRAME_GLOBAL)
    )
    for item in m.items[1:]:
        wp = loader.wp(item.seq)
        assert (wp.command, wp.frame) == (item.command, item.frame)
        assert wp.z == pytest.approx(item.z, abs=5e-7)
    ours = loads_waypoints(path.read_text())
    assert ours.home == pytest.approx((HOME.lat, HOME.lon, HOME.alt), abs=1e-8)
    assert len(ours.items) == loader.count()


def test_a_px4_waypoints_file_is_refused_with_the_reason(plan_file, tmp_path, capsys):
    out = tmp_path / "m.waypoints"
    args = ["export", str(plan_file), "--format", "waypoints", "--autopilot", "px4"]
    assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "QGroundControl" in err and "pymavlink" in err and "--format plan" in err
    assert "\n" not in err and not out.exists()
