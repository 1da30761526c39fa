"""One aircraft from plan to flight (issue 49): the plan's vehicle setup is written beside the
mission in the files ground stations load, upload checks the vehicle against it (and sets it
with --params), and the dry run flies the operator's whole workflow: plan, mission and setup,
upload both, fly. A vehicle left at its own parameters is named as the cause of its loss."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from gcs_planner.sim.navigators.params import AutopilotParams
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from pymavlink.mavparm import MAVParmDict
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.aircraft.profile import tas_from_eas
from gcs_planner.cli import main
from gcs_planner.errors import InputError
from gcs_planner.mission import param_files
from gcs_planner.mission.vehicle_setup import needs

COAST = "missions/coast/scenario.toml"
EXAMPLE = "missions/example/scenario.toml"


@pytest.fixture(scope="module")
def coast_plans(tmp_path_factory) -> dict[str, Path]:
    """plan --out of the coast example for each autopilot (ArduPilot: the default)."""
    out = {}
    with pytest.MonkeyPatch.context() as patch:
        leave_pictures_undrawn(patch)  # the setup and the missions are read, not the pictures
        for firmware in ("ardupilot", "px4"):
            folder = tmp_path_factory.mktemp(firmware) / "coast"
            extra = [] if firmware == "ardupilot" else ["--autopilot", "px4"]
            assert main(["plan", COAST, "--out", str(folder), "--quiet", *extra]) == 0
            out[firmware] = folder
    return out


def _by_name(plan: dict, firmware: str) -> dict:
    return {n.name: n for n in needs(plan, firmware)}


def test_setup_needs_follow_the_stated_aircraft(coast_plans):
    """The coast aircraft (25 m/s EAS, 15 deg climbs, 200 m radius) at its highest landmark:
    the rates are Vg tan(15 deg), the bank atan(Vg^2 / (g R)), each autopilot's own names."""
    plan = json.loads((coast_plans["ardupilot"] / "plan.json").read_text())
    top = max(p["z"] for p in plan["points"])
    vg = tas_from_eas(25.0, top)
    ap = _by_name(plan, "ardupilot")
    assert ap["AIRSPEED_CRUISE"].set_to == 25.0
    assert ap["AIRSPEED_MAX"].least == 25.0 and ap["AIRSPEED_MAX"].set_to >= 25.0
    assert ap["TECS_CLMB_MAX"].least == pytest.approx(vg * math.tan(math.radians(15)))
    assert ap["TECS_SINK_MAX"].least == pytest.approx(vg * math.tan(math.radians(15)))
    bank = math.degrees(math.atan(vg * vg / (9.80665 * 200.0)))
    assert ap["ROLL_LIMIT_DEG"].least == pytest.approx(bank)
    assert ap["NAVL1_LIM_BANK"].least == pytest.approx(bank)
    assert ap["WP_LOITER_RAD"].set_to == 200.0
    # The shipped limits fall short: the vehicle must be set up for this aircraft.
    assert not ap["TECS_CLMB_MAX"].met_by(5.0) and ap["TECS_CLMB_MAX"].met_by(8.0)
    assert not ap["AIRSPEED_MAX"].met_by(22.0)
    assert ap["AIRSPEED_MIN"].met_by(9.0) and not ap["AIRSPEED_MIN"].met_by(26.0)
    px4 = _by_name(json.loads((coast_plans["px4"] / "plan.json").read_text()), "px4")
    assert {"FW_AIRSPD_TRIM", "FW_T_CLMB_R_SP", "FW_T_CLMB_MAX", "FW_R_LIM"} <= set(px4)
    assert not set(px4) & set(ap)  # each autopilot's own names only
    # PX4 holds the landmark's altitude on the run-out: its rates cover at least the angle's
    assert px4["FW_T_CLMB_R_SP"].least >= vg * math.tan(math.radians(15)) - 1e-9


def test_plan_out_writes_the_setup_for_its_autopilot(coast_plans):
    for firmware, folder in coast_plans.items():
        names = {n.name for n in needs(json.loads((folder / "plan.json").read_text()), firmware)}
        setup = param_files.read(folder / "vehicle.param")
        assert setup.autopilot == firmware
        assert set(setup.values) == names
        qgc = param_files.read(folder / "vehicle.params")
        assert qgc.values == pytest.approx(setup.values)
        listed = json.loads((folder / "plan.json").read_text())["setup"]
        assert listed["autopilot"] == firmware and listed["flyable"] is True
        assert {p["name"] for p in listed["parameters"]} == names
    assert "TECS_CLMB_MAX" in (coast_plans["ardupilot"] / "vehicle.param").read_text()
    assert "FW_T_CLMB_R_SP" in (coast_plans["px4"] / "vehicle.param").read_text()
    # the mission is the target autopilot's: PX4 has no home item and no .waypoints
    px4_plan = json.loads((coast_plans["px4"] / "mission.plan").read_text())
    assert px4_plan["mission"]["firmwareType"] == 12
    assert not (coast_plans["px4"] / "mission.waypoints").exists()


def test_param_file_loads_in_pymavlink(coast_plans):
    """MAVProxy's `param load` (pymavlink's MAVParmDict.load) reads the .param as written."""
    path = coast_plans["ardupilot"] / "vehicle.param"
    theirs = MAVParmDict()
    assert theirs.load(str(path))
    ours = param_files.read(path).values
    assert dict(theirs) == pytest.approx(ours)


@pytest.mark.parametrize(
    ("text", "row", "field"),
    [
        ("TECS_CLMB_MAX,fast\n", 1, "TECS_CLMB_MAX"),
        ("# c\nTECS_CLMB_MAX,8\nTECS_CLMB_MAX,9\n", 3, "TECS_CLMB_MAX"),
        ("TECS_CLMB_MAX\n", 1, None),
        ("A_NAME_MUCH_TOO_LONG,1\n", 1, "name"),
        ("X,nan\n", 1, "X"),
    ],
)
def test_bad_setup_file_names_file_row_and_field(tmp_path, text, row, field):
    path = tmp_path / "bad.param"
    path.write_text(text)
    with pytest.raises(InputError) as caught:
        param_files.read(path)
    assert caught.value.file == str(path) and caught.value.row == row
    assert caught.value.field == field


def test_upload_checks_the_vehicle_then_sets_the_setup(coast_plans, capsys):
    """A mock at its shipped parameters is refused, naming what falls short, and nothing is
    uploaded; with --params the setup is set, read back, and the mission goes up."""
    folder = coast_plans["ardupilot"]
    mission = folder / "mission.waypoints"
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="ardupilot") as vehicle:
        before = list(vehicle.mission)
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet"]
        assert main(["upload", str(mission), *conn]) == 4
        err = capsys.readouterr().err
        assert "TECS_CLMB_MAX is 5" in err and "--params" in err and "Traceback" not in err
        assert list(vehicle.mission) == before
        setup = folder / "vehicle.param"
        assert main(["upload", "--params", str(setup), str(mission), *conn]) == 0
        out, err = capsys.readouterr()
        assert "verified" in out and "set and read back" in err
        for name, value in param_files.read(setup).values.items():
            assert vehicle.parameters[name] == pytest.approx(value, abs=1e-3)
        assert len(vehicle.mission) > len(before)
        # set up, the same mission now passes the check without --params
        assert main(["upload", str(mission), *conn]) == 0


def test_upload_refuses_a_setup_for_the_other_autopilot(coast_plans, capsys):
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4"):
        rc = main(["upload", "--params", str(coast_plans["ardupilot"] / "vehicle.param"),
                   str(coast_plans["ardupilot"] / "mission.plan"),
                   "--connect", f"udpout:127.0.0.1:{port}", "--quiet"])  # fmt: skip
    assert rc == 4
    assert "runs px4" in capsys.readouterr().err


@pytest.mark.parametrize("firmware", ["ardupilot", "px4"])
@pytest.mark.parametrize("scenario", [COAST, EXAMPLE])
def test_bundled_examples_fly_on_both_autopilots(scenario, firmware, capsys):
    """Every bundled example, default flags: verified, no run lost by the flight."""
    rc = main(["dry-run", scenario, "--autopilot", firmware, "--runs", "12", "--json", "--quiet"])
    report = json.loads(capsys.readouterr().out)
    assert report["verified"] and report["flight_losses"] == 0, report["lost_runs"][:3]
    assert report["setup_shortfalls"] == [] and report["setup"]
    assert report["verdict"].startswith("VERDICT: GO")
    assert rc == 0


def test_a_vehicle_as_is_is_named_as_the_cause(capsys):
    rc = main(["dry-run", COAST, "--runs", "4", "--vehicle-as-is", "--quiet"])
    out, err = capsys.readouterr()
    assert rc == 5
    assert "first cause: the vehicle is not set up for the plan: TECS_CLMB_MAX is 5" in err
    assert "NO GO" in out.splitlines()[-1]


def test_nothing_is_said_of_flights_that_never_flew(capsys, monkeypatch):
    """A refused upload: exit 4, no success rate, no lost runs, the verdict says nothing flew."""
    from gcs_planner.errors import LinkError
    from gcs_planner.link import mission_client

    def refuse(self, *a, **k):  # noqa: ANN001, ANN002, ANN003
        raise LinkError("upload refused: MAV_MISSION_NO_SPACE")

    monkeypatch.setattr(mission_client.MissionClient, "upload_verified", refuse)
    rc = main(["dry-run", COAST, "--runs", "5", "--quiet"])
    out, _ = capsys.readouterr()
    assert rc == 4
    assert "success rate" not in out and "lost by the flight" not in out
    assert out.splitlines()[-1].startswith("VERDICT: NOT VERIFIED")


def test_arduplane_ignores_and_px4_clamps_a_speed_outside_its_range():
    ap = AutopilotParams("ardupilot")  # AIRSPEED_MIN 9, AIRSPEED_MAX 22 as shipped
    assert ap.commanded_airspeed(25.0) is None and ap.commanded_airspeed(20.0) == 20.0
    px4 = AutopilotParams("px4")  # FW_AIRSPD_MIN 10, FW_AIRSPD_MAX 20 as shipped
    assert px4.commanded_airspeed(25.0) == 20.0 and px4.commanded_airspeed(5.0) == 10.0
    set_up = AutopilotParams.from_parameters("ardupilot", {"AIRSPEED_MAX": 30.0})
    assert set_up.commanded_airspeed(25.0) == 25.0


def test_a_stated_envelope_is_set_up_for_its_design_wind(tmp_path, monkeypatch):
    """plan --wind 5 of the coast (angles stated, not derived): the setup climbs at the
    angles over the fastest ground speed, TAS + 5, as a downwind leg flies them."""
    out = tmp_path / "windy"
    leave_pictures_undrawn(monkeypatch)  # the setup is the subject here
    assert main(["plan", COAST, "--wind", "5", "--out", str(out), "--quiet"]) == 0
    plan = json.loads((out / "plan.json").read_text())
    vg = tas_from_eas(25.0, max(p["z"] for p in plan["points"])) + 5.0
    listed = {p["name"]: p for p in plan["setup"]["parameters"]}
    assert listed["TECS_CLMB_MAX"]["least"] == pytest.approx(vg * math.tan(math.radians(15)))
    assert param_files.read(out / "vehicle.param").values["TECS_CLMB_MAX"] >= vg * math.tan(
        math.radians(15)
    )
