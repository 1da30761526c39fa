"""`plan --vehicle-from CONNECT`: the envelope read from the autopilot's parameters (ArduPlane's
and PX4's own names) becomes the planner's cruise airspeed, bank limit and climb/descent angles."""

from __future__ import annotations

import pytest

import gcs_planner.cli.plan as plan_cli
from gcs_planner.autopilot import effective
from gcs_planner.cli import main
from gcs_planner.vehicle import ENVELOPE_PARAMS
from sim.param_server import parameter_table
from sim.vehicle import MockVehicle, free_udp_port

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
    # descent angle is derived after the scenario loads (tests/test_vehicle_profile.py)
    sink = effective(flavour, {k: v[0] for k, v in table.items()}).sink_rate
    assert seen["max_sink_rate"] == pytest.approx(sink)
    assert seen["max_descent_angle"] is None
    assert seen["max_climb_angle"] == 20.0  # a flag wins over the autopilot
    assert f"from the {flavour} vehicle" in err
