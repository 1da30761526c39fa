"""Upload checks the vehicle's parameters against what the plan's envelope needs (issue 32),
over real MAVLink to the mock vehicle on 127.0.0.1: a vehicle that climbs slower, banks less or
(ArduPlane) widens its loiters with altitude is refused with the parameter, its value and the
plan's need named, and nothing is uploaded; ``--set-params`` lists and sets them, then uploads."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.cli import main
from gcs_planner.link.vehicle_check import needs

DS1 = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
       "--delta", "0.001"]  # fmt: skip


def _plan(tmp_path: Path, capsys, dataset_paths, *extra: str) -> Path:
    rc = main(["plan", str(dataset_paths[1]), *DS1, "--json", "--quiet", *extra])
    out = capsys.readouterr().out
    assert rc == 0
    path = tmp_path / "plan.json"
    path.write_text(out)
    return path


def _upload(vehicle_port: int, plan: Path, *extra: str) -> int:
    return main(
        ["upload", str(plan), "--connect", f"udpout:127.0.0.1:{vehicle_port}", "--quiet", *extra]
    )


def test_arduplane_loiters_widened_with_altitude_are_refused_then_set(
    tmp_path, capsys, dataset_paths
):
    plan = _plan(tmp_path, capsys, dataset_paths, "--firmware", "ardupilot")
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="ardupilot") as vehicle:
        assert vehicle.parameters["NAVL1_LIM_BANK"] == 0.0  # the shipped default
        before = list(vehicle.mission)  # ArduPilot holds its home as item 0
        assert _upload(port, plan) == 4
        err = capsys.readouterr().err
        assert "NAVL1_LIM_BANK is 0" in err and "--set-params" in err and "Traceback" not in err
        assert list(vehicle.mission) == before  # nothing uploaded
        assert _upload(port, plan, "--set-params") == 0
        out, err = capsys.readouterr()
        assert "will set NAVL1_LIM_BANK" in err and "verified" in out
        env = json.loads(plan.read_text())["vehicle"]["envelope"]
        (need,) = [n for n in needs(json.loads(plan.read_text()), "ardupilot")
                   if n.name == "NAVL1_LIM_BANK"]  # fmt: skip
        assert vehicle.parameters["NAVL1_LIM_BANK"] == pytest.approx(need.set_to, abs=1e-3)
        # ArduPlane's loiter_radius then keeps the plan's radius at the highest point's TAS
        limit = vehicle.parameters["NAVL1_LIM_BANK"]
        import math

        tas, radius = env["tas"], env["turn_radius"]
        assert tas * tas / (9.80665 * math.tan(math.radians(limit))) <= radius + 1e-6
        assert len(vehicle.mission) > len(before)
        # set up now: a second upload passes without --set-params
        assert _upload(port, plan) == 0


def test_px4_climbing_slower_than_the_plan_is_refused_naming_the_parameter(
    tmp_path, capsys, dataset_paths
):
    plan = _plan(tmp_path, capsys, dataset_paths, "--firmware", "px4", "--max-climb-rate", "4")
    (need,) = [n for n in needs(json.loads(plan.read_text()), "px4")
               if n.name == "FW_T_CLMB_R_SP"]  # fmt: skip
    # at least the plan's rate; more where a leg's climb must fit after PX4's level run-out
    assert need.least >= 4.0
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        before = list(vehicle.mission)
        assert _upload(port, plan) == 4
        err = capsys.readouterr().err
        # PX4 climbs in missions at FW_T_CLMB_R_SP (3 m/s shipped), bounded by FW_T_CLMB_MAX
        assert "FW_T_CLMB_R_SP is 3" in err and f"at least {need.least:.4g}" in err
        assert list(vehicle.mission) == before
        assert _upload(port, plan, "--set-params") == 0
        assert vehicle.parameters["FW_T_CLMB_R_SP"] == pytest.approx(need.set_to, abs=1e-4)
        # the bound is raised only as far as the need, and never below its shipped 5 m/s
        assert vehicle.parameters["FW_T_CLMB_MAX"] == pytest.approx(max(5.0, need.set_to))


def test_a_plan_stated_as_angles_and_a_radius_needs_their_rates(tmp_path, capsys, dataset_paths):
    """Stated angles name no rates, but the aircraft still climbs at Vg tan(angle): the
    vehicle is checked for them as for a derived envelope, and set with --set-params."""
    plan = _plan(tmp_path, capsys, dataset_paths, "--turn-radius", "200",
                 "--max-climb-angle", "15", "--max-descent-angle", "15")  # fmt: skip
    data = json.loads(plan.read_text())
    by_name = {n.name: n for n in needs(data, "ardupilot")}
    top = max(p["z"] for p in data["points"])
    from gcs_planner.aircraft.profile import tas_from_eas

    vg = tas_from_eas(data["vehicle"]["cruise_airspeed"], top)
    assert by_name["TECS_CLMB_MAX"].least == pytest.approx(vg * math.tan(math.radians(15)))
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="ardupilot") as vehicle:
        assert _upload(port, plan) == 4
        assert "TECS_CLMB_MAX is 5" in capsys.readouterr().err
        assert _upload(port, plan, "--set-params") == 0
        assert len(vehicle.mission) > 1
        assert vehicle.parameters["TECS_CLMB_MAX"] >= by_name["TECS_CLMB_MAX"].least
