"""The envelope derived from the autopilot's terms (issue 32): TAS from EAS through ISA at the
scenario's highest altitude, climb/descent angle = atan(rate / (TAS + W)), turning radius
R = (TAS + W)^2 / (g tan(bank)); flags, firmware defaults, ``--vehicle-from`` (PX4's mission
rates), bad values, and direct statements that leave today's fronts unchanged."""

from __future__ import annotations

import json
import math

import pytest
from gcs_planner.sim.param_server import parameter_table
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

import gcs_planner.cli.plan as plan_cli
from gcs_planner.aircraft.profile import (
    DerivedEnvelope,
    isa_density_ratio,
    parse_wind,
    tas_from_eas,
)
from gcs_planner.cli import main

ROWS = [("P0", 0, 0, "A", 0), ("P1", 12_000, 300, "V", 0), ("P2", 24_000, 0, "H", 0),
        ("P3", 36_000, 300, "V", 0), ("P4", 48_000, 0, "B", 0)]  # fmt: skip
FLAGS = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
         "--delta", "0.001"]  # fmt: skip
G = 9.80665


@pytest.fixture
def line_csv(tmp_path):
    csv = tmp_path / "line.csv"
    lines = ["id,x,y,z,kind,unreliable"]
    lines += [f"{i},{x},{y},{3000 + (400 if k == 'V' else 0)},{k},{u}" for i, x, y, k, u in ROWS]
    csv.write_text("\n".join(lines) + "\n")
    return csv


def plan_json(args, capsys) -> dict:
    code = main(["plan", *args, "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out)


def test_isa_and_tas_against_hand_computation():
    assert isa_density_ratio(0.0) == 1.0
    # 5000 m: T = 288.15 - 32.5 = 255.65 K; sigma = (255.65 / 288.15)^4.2559 = 0.6009
    assert isa_density_ratio(5000.0) == pytest.approx(0.6009, abs=2e-4)
    assert tas_from_eas(20.0, 5000.0) == pytest.approx(20.0 / math.sqrt(0.6009), rel=2e-4)
    # above the tropopause the temperature holds (216.65 K) and the density falls as
    # exp(-g dh / (R T11)): 1 km higher, 0.8541 of 11 km's; below sea level, sea level's
    assert isa_density_ratio(12_000.0) == pytest.approx(
        isa_density_ratio(11_000.0) * math.exp(-9.80665 * 1000 / (287.05287 * 216.65)), rel=1e-12
    )
    assert isa_density_ratio(-50.0) == 1.0


def test_angles_and_radius_against_hand_computation():
    env = DerivedEnvelope(20.0, 45.0, 5.0, 2.0, 5.0, None, 5000.0, "ardupilot")
    v = 20.0 / math.sqrt(0.6009) + 5.0  # TAS + W, about 30.80 m/s
    assert env.ground_speed_max == pytest.approx(v, rel=2e-4)
    assert env.climb_angle == pytest.approx(math.degrees(math.atan(5.0 / v)), rel=1e-3)
    assert env.descent_angle == pytest.approx(math.degrees(math.atan(2.0 / v)), rel=1e-3)
    assert env.turn_radius == pytest.approx(v * v / G, rel=1e-3)  # tan 45 = 1
    still = DerivedEnvelope(20.0, 45.0, 5.0, 2.0, 0.0, None, 0.0, None)
    assert still.turn_radius == pytest.approx(400.0 / G)


def test_wind_text():
    assert parse_wind("5") == (5.0, None)
    assert parse_wind("7.5@370") == (7.5, 10.0)
    for bad in ("-1", "x", "5@north", "inf"):
        with pytest.raises(ValueError):
            parse_wind(bad)


def test_firmware_defaults_derive_the_envelope(line_csv, capsys):
    got = plan_json([str(line_csv), *FLAGS, "--firmware", "px4"], capsys)
    env = got["vehicle"]["envelope"]
    # PX4 ships FW_AIRSPD_TRIM 15, FW_R_LIM 50, mission rates min(3, 5) and min(2, 5)
    assert env["cruise_eas"] == 15.0 and env["bank_limit_deg"] == 50.0
    assert (env["climb_rate"], env["sink_rate"]) == (3.0, 2.0)
    assert env["altitude_m"] == 3400.0
    v = tas_from_eas(15.0, 3400.0)
    assert env["tas"] == pytest.approx(v)
    params = got["parameters"]
    assert params["turn_radius"] == pytest.approx(v * v / (G * math.tan(math.radians(50))))
    assert params["max_climb_angle"] == pytest.approx(math.degrees(math.atan(3.0 / v)))
    assert params["max_descent_angle"] == pytest.approx(math.degrees(math.atan(2.0 / v)))


def test_flags_win_over_firmware_and_wind_widens_everything(line_csv, capsys):
    args = [str(line_csv), *FLAGS, "--firmware", "ardupilot", "--cruise-airspeed", "22",
            "--max-climb-rate", "4", "--wind", "6@90"]  # fmt: skip
    got = plan_json(args, capsys)
    env = got["vehicle"]["envelope"]
    v = tas_from_eas(22.0, 3400.0) + 6.0
    assert env["cruise_eas"] == 22.0 and env["climb_rate"] == 4.0
    assert env["sink_rate"] == 5.0  # ArduPlane's TECS_SINK_MAX default
    assert env["design_wind"] == 6.0 and env["design_wind_from_deg"] == 90.0
    assert env["ground_speed_max"] == pytest.approx(v)
    assert got["parameters"]["turn_radius"] == pytest.approx(v * v / G)  # 45 deg bank
    assert got["parameters"]["max_climb_angle"] == pytest.approx(math.degrees(math.atan(4 / v)))


def test_text_output_says_how_each_figure_was_derived(line_csv, capsys):
    code = main(["plan", str(line_csv), *FLAGS, "--firmware", "px4", "--wind", "5@270"])
    out = capsys.readouterr().out
    assert code == 0
    assert "ISA, the scenario's highest altitude: conservative for every leg" in out
    assert "per leg" not in out
    assert "from 270 deg: each leg's climb and descent along its own track" in out
    assert "R = (TAS + W)^2 / (g tan 50 deg)" in out
    assert "max_climb_rate from px4's shipped default" in out


def test_text_output_of_a_per_leg_envelope(line_csv, capsys):
    code = main(["plan", str(line_csv), *FLAGS, "--firmware", "ardupilot", "--wind", "5",
                 "--per-leg-envelope"])  # fmt: skip
    out = capsys.readouterr().out
    assert code == 0
    assert (
        "ISA, the scenario's highest altitude; each leg flies within the figures of its own "
        "highest point, these at the top" in out
    )
    # the line's points lie at 3 km and 3.4 km: the lowest legs' figures are printed too
    assert "per leg, from the TAS at its highest point: at the lowest point (3000 m" in out
    assert "climb " in out.split("at the lowest point (3000 m")[1].splitlines()[0]


def test_direct_statements_leave_the_front_unchanged(line_csv, capsys):
    # The straight runs at the landmarks are derived for the target autopilot (ArduPilot unless
    # --firmware) unless stated: stated too, nothing is left to derive.
    direct = ["--turn-radius", "300", "--max-climb-angle", "12", "--max-descent-angle", "10",
              "--approach", "150", "--departure", "150"]  # fmt: skip
    before = plan_json([str(line_csv), *FLAGS, *direct], capsys)
    after = plan_json([str(line_csv), *FLAGS, *direct, "--firmware", "px4", "--wind", "5"],
                      capsys)  # fmt: skip
    assert before["vehicle"]["envelope"] is None
    assert after["vehicle"]["envelope"] is None  # nothing derived: today's plan, said so
    assert after["parameters"] == before["parameters"]
    assert after["front"] == before["front"]


def test_runs_follow_the_target_autopilot_of_a_stated_envelope(line_csv, capsys):
    """A stated envelope keeps its radius and angles under any autopilot; the runs at the
    landmarks are the target autopilot's settle distance at the largest ground speed."""
    direct = ["--turn-radius", "300", "--max-climb-angle", "12", "--max-descent-angle", "10"]
    ardu = plan_json([str(line_csv), *FLAGS, *direct], capsys)["parameters"]
    px4 = plan_json([str(line_csv), *FLAGS, *direct, "--firmware", "px4"], capsys)["parameters"]
    for key in ("turn_radius", "max_climb_angle", "max_descent_angle"):
        assert ardu[key] == px4[key]
    # no airspeed stated: the scenario's default 25 m/s, or PX4's shipped 15 with --firmware
    assert ardu["approach"] == pytest.approx(17 * 0.75 * tas_from_eas(25.0, 3400.0) / math.pi)
    assert px4["approach"] == pytest.approx(10 * 0.7 * tas_from_eas(15.0, 3400.0))
    assert ardu["departure"] == ardu["approach"] and px4["departure"] == px4["approach"]


def test_the_wind_scales_a_stated_radius_when_no_bank_is_given(line_csv, capsys):
    still = plan_json([str(line_csv), *FLAGS], capsys)
    windy = plan_json([str(line_csv), *FLAGS, "--wind", "5"], capsys)
    v = tas_from_eas(25.0, 3400.0)
    r = still["parameters"]["turn_radius"]
    assert windy["parameters"]["turn_radius"] == pytest.approx(r * ((v + 5) / v) ** 2)
    # no rate given: the climb stays unlimited, and the plan still says it assumed so
    assert windy["parameters"]["max_climb_angle"] == 90.0
    assert any("unlimited" in w or "assum" in w for w in windy["warnings"])


@pytest.mark.parametrize(
    "extra, flag",
    [
        (["--max-climb-rate", "-1"], "--max-climb-rate"),
        (["--max-sink-rate", "0"], "--max-sink-rate"),
        (["--max-bank-angle", "90", "--max-climb-rate", "3"], "--max-bank-angle"),
        (["--wind", "40", "--cruise-airspeed", "20"], "--wind"),
        (["--wind", "fast"], "--wind"),
    ],
)
def test_bad_values_are_one_line_errors_naming_the_flag(line_csv, capsys, extra, flag):
    code = main(["plan", str(line_csv), *FLAGS, *extra])
    err = capsys.readouterr().err
    assert code == 2
    # the flag, or its field as the scenario reader names a command-line value
    assert flag in err or flag[2:].replace("-", "_") in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_px4_vehicle_gives_its_mission_rates(line_csv, monkeypatch, capsys):
    """PX4 climbs in missions at min(FW_T_CLMB_R_SP, FW_T_CLMB_MAX) and sinks at
    min(FW_T_SINK_R_SP, FW_T_SINK_MAX), not at the maxima (issue 32)."""
    seen = {}
    original = plan_cli.derive_envelope

    def spy(args, *rest, **kw):
        seen.update(vars(args))
        return original(args, *rest, **kw)

    monkeypatch.setattr(plan_cli, "derive_envelope", spy)
    table = parameter_table("px4")
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4"):
        got = plan_json([str(line_csv), *FLAGS, "--vehicle-from", f"udpout:127.0.0.1:{port}"],
                        capsys)  # fmt: skip
    climb = min(table["FW_T_CLMB_R_SP"][0], table["FW_T_CLMB_MAX"][0])
    sink = min(table["FW_T_SINK_R_SP"][0], table["FW_T_SINK_MAX"][0])
    assert sink < table["FW_T_SINK_MAX"][0]  # the setpoint is what tells the two apart
    assert seen["max_climb_rate"] == pytest.approx(climb)
    assert seen["max_sink_rate"] == pytest.approx(sink)
    env = got["vehicle"]["envelope"]
    assert env["sink_rate"] == pytest.approx(sink)
    assert env["sources"]["max_sink_rate"] == "the px4 vehicle"


def test_the_scenario_toml_states_the_autopilot_terms_and_environment(line_csv, capsys):
    toml = line_csv.parent / "s.toml"
    toml.write_text(
        'points = "line.csv"\n[parameters]\nalpha1 = 25\nalpha2 = 15\nbeta1 = 20\nbeta2 = 25\n'
        'theta = 30\ndelta = 0.001\n[vehicle]\nfirmware = "px4"\nmax_climb_rate = 4\n'
        '[environment]\nwind = "5@180"\ncapture_radius = 2\nerror_unit = 0.05\n'
    )
    got = plan_json([str(toml)], capsys)
    env = got["vehicle"]["envelope"]
    assert env["climb_rate"] == 4.0 and env["sources"]["max_climb_rate"] == str(toml)
    assert env["sink_rate"] == 2.0  # PX4's FW_T_SINK_R_SP default fills what the file leaves
    assert env["design_wind"] == 5.0 and env["design_wind_from_deg"] == 180.0
    assert got["capture"]["capture_radius_m"] == 2.0 and got["capture"]["error_unit_m"] == 0.05
    # a flag wins over the file
    got = plan_json([str(toml), "--max-climb-rate", "3", "--wind", "0"], capsys)
    assert got["vehicle"]["envelope"]["climb_rate"] == 3.0
    assert got["vehicle"]["envelope"]["design_wind"] == 0.0


@pytest.mark.parametrize(
    "line, field",
    [("[vehicle]\nmax_sink_rate = -1\n", "vehicle.max_sink_rate"),
     ('[vehicle]\nfirmware = "inav"\n', "vehicle.firmware"),
     ('[environment]\nwind = "fast"\n', "environment.wind"),
     ("[environment]\ncapture_radius = 0\n", "environment.capture_radius")],
)  # fmt: skip
def test_bad_toml_terms_name_file_line_and_field(line_csv, capsys, line, field):
    toml = line_csv.parent / "s.toml"
    toml.write_text('points = "line.csv"\n' + line)
    assert main(["plan", str(toml)]) == 2
    err = capsys.readouterr().err
    assert field in err and str(toml) in err and "row 3" in err and "Traceback" not in err
