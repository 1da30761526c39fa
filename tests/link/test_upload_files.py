"""What `upload` makes of the files a user hands it: a PX4 .waypoints is PX4's, and a plan JSON
whose loiter radius the vehicle cannot hold is refused before anything is uploaded."""

from __future__ import annotations

from pathlib import Path

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.cli import main

ROWS = [("P0", 0, 0, "A", 0), ("P1", 12_000, 300, "V", 0), ("P2", 24_000, 0, "H", 0),
        ("P3", 36_000, 300, "V", 0), ("P4", 48_000, 0, "B", 0)]  # fmt: skip
FLAGS = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
         "--delta", "0.001", "--turn-radius", "200", "--origin", "30.5,123.5"]  # fmt: skip


@pytest.fixture(scope="module")
def plan_json(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("plan")
    csv = folder / "line.csv"
    lines = ["id,x,y,z,kind,unreliable"]
    lines += [f"{i},{x},{y},5000,{k},{u}" for i, x, y, k, u in ROWS]
    csv.write_text("\n".join(lines) + "\n")
    assert main(["plan", str(csv), *FLAGS, "--json", "--out", str(folder / "out")]) == 0
    return folder / "out" / "plan.json"


def test_a_px4_waypoints_file_is_uploaded_to_a_px4_vehicle(plan_json, tmp_path, capsys):
    # gcs-planner no longer writes PX4 .waypoints (readers disagree on row 0); files written by
    # earlier releases (row 0 home, the items from row 1) are still uploaded as QGC reads them.
    from gcs_planner.mission.builder import build_mission
    from gcs_planner.mission.plan_json import load_plan
    from gcs_planner.mission.waypoints import dumps_items

    m = build_mission(load_plan(plan_json), firmware="px4")
    wp = tmp_path / "px4.waypoints"
    wp.write_text(dumps_items(m.items, "px4", m.home))
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet"]
        assert main(["upload", str(wp), *conn]) == 0, capsys.readouterr().err
        rows = [line for line in wp.read_text().splitlines()[2:] if line.strip()]
        assert len(vehicle.mission) == len(rows)  # row 0 is home, not a PX4 item


def test_plan_json_to_a_vehicle_without_the_loiter_parameter(plan_json, capsys):
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        del vehicle.params.table["NAV_LOITER_RAD"]
        conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet", "--timeout", "0.3"]
        assert main(["upload", str(plan_json), *conn]) == 4  # built for the vehicle's PX4
        err = capsys.readouterr().err.strip()
        # the vehicle setup names it first, among what the vehicle is not set up for
        assert "NAV_LOITER_RAD is not on the vehicle" in err and "\n" not in err
        assert "Nothing was uploaded" in err
        # past the setup check, the loiter radius the upload sets is checked on its own
        assert main(["upload", str(plan_json), *conn, "--no-param-check"]) == 4
        err = capsys.readouterr().err.strip()
        assert "NAV_LOITER_RAD" in err and "nothing was uploaded" in err and "\n" not in err
        assert vehicle.mission == []
        args = [str(plan_json), *conn, "--keep-loiter-radius", "--no-param-check"]
        assert main(["upload", *args]) == 0
        assert len(vehicle.mission) > 2
