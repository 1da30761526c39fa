"""`plan --vehicle-from CONNECT`: the envelope read from the autopilot's parameters (ArduPlane's
and PX4's own names) becomes the planner's cruise airspeed, bank limit and climb/descent angles."""

from __future__ import annotations

import pytest
from gcs_planner.sim.param_server import parameter_table
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

import gcs_planner.cli.plan as plan_cli
from gcs_planner.aircraft.autopilot import effective
from gcs_planner.aircraft.profile import ENVELOPE_PARAMS
from gcs_planner.cli import main

ROWS = [("P0", 0, 0, "A", 0), ("P1", 12_000, 300, "V", 0), ("P2", 24_000, 0, "H", 0),
        ("P3", 36_000, 300, "V", 0), ("P4", 48_000, 0, "B", 0)]  # fmt: skip
FLAGS = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
         "--delta", "0.001"]  # fmt: skip


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_plan_reads_the_envelope_from_the_vehicle(flavour, tmp_path, monkeypatch, capsys):
    csv = tmp_path / "line.csv"
    lines = ["id,x,y,z,kind,unreliable"]
    lines += [f"{i},{x},{y},5000,{k},{u}" for i, x, y, k, u in ROWS]
    csv.write_text("\n".join(lines) + "\n")
    seen = {}
    original = plan_cli.load_scenario_from_args

    def spy(args, *rest):
        seen.update(vars(args))
        return original(args, *rest)

    monkeypatch.setattr(plan_cli, "load_scenario_from_args", spy)
    table = parameter_table(flavour)
    names = ENVELOPE_PARAMS[flavour]
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour):
        code = main(["plan", str(csv), *FLAGS, "--vehicle-from", f"udpout:127.0.0.1:{port}",
                     "--max-climb-angle", "20", "--json"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 0, err
    airspeed = table[names["cruise_airspeed"]][0]
    assert seen["cruise_airspeed"] == pytest.approx(airspeed)
    assert seen["max_bank_angle"] == pytest.approx(table[names["bank_limit"]][0])
    # the rate a mission sinks at (PX4: min(FW_T_SINK_R_SP, FW_T_SINK_MAX)), from which the
    # descent angle is derived after the scenario loads (tests/aircraft/test_vehicle_profile.py)
    sink = effective(flavour, {k: v[0] for k, v in table.items()}).sink_rate
    assert seen["max_sink_rate"] == pytest.approx(sink)
    assert seen["max_descent_angle"] is None
    assert seen["max_climb_angle"] == 20.0  # a flag wins over the autopilot
    assert f"from the {flavour} vehicle" in err


@pytest.mark.parametrize(("flavour", "period"), [("ardupilot", "NAVL1_PERIOD"),
                                                 ("px4", "NPFG_PERIOD")])  # fmt: skip
def test_the_runs_and_the_reserve_follow_the_vehicles_own_guidance_tuning(
    flavour, period, tmp_path, capsys
):
    """A vehicle whose path follower is tuned slower than shipped (period 25 s): the plan's
    run-in and run-out are its settle distance with that period, not the shipped one, and the
    derived reserve's turn entry (ArduPlane: L1/2) says the vehicle's value."""
    import json

    csv = tmp_path / "line.csv"
    lines = ["id,x,y,z,kind,unreliable"]
    lines += [f"{i},{x},{y},5000,{k},{u}" for i, x, y, k, u in ROWS]
    csv.write_text("\n".join(lines) + "\n")
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour) as vehicle:
        value, ptype = vehicle.params.table[period]
        vehicle.params.table[period] = (25.0, ptype)
        code = main(["plan", str(csv), *FLAGS, "--vehicle-from", f"udpout:127.0.0.1:{port}",
                     "--json", "--quiet"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0, err
    assert value != 25.0 and f"{period} 25" in err
    plan = json.loads(out)
    env = plan["vehicle"]["envelope"]
    table = {k: v[0] for k, v in parameter_table(flavour).items()}
    tuned = effective(flavour, {**table, period: 25.0}).settle_distance(env["ground_speed_max"])
    shipped = effective(flavour, table).settle_distance(env["ground_speed_max"])
    assert env["approach_m"] == pytest.approx(tuned) and tuned > 1.2 * shipped
    assert f"{period} 25" in env["runs_source"]
    if flavour == "ardupilot":
        assert f"{period} 25" in plan["reserve"]["late_entry_rule"]


def test_a_guidance_parameter_out_of_its_range_is_refused_by_name(tmp_path, capsys):
    csv = tmp_path / "line.csv"
    lines = ["id,x,y,z,kind,unreliable"]
    lines += [f"{i},{x},{y},5000,{k},{u}" for i, x, y, k, u in ROWS]
    csv.write_text("\n".join(lines) + "\n")
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="ardupilot") as vehicle:
        _, ptype = vehicle.params.table["NAVL1_DAMPING"]
        vehicle.params.table["NAVL1_DAMPING"] = (0.2, ptype)  # ArduPilot's range: 0.6..1
        code = main(["plan", str(csv), *FLAGS, "--vehicle-from", f"udpout:127.0.0.1:{port}",
                     "--json", "--quiet"])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 4 and out == ""
    assert "NAVL1_DAMPING 0.2" in err and "0.6..1" in err and "Traceback" not in err
