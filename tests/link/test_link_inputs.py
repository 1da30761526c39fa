"""Bad input on the way in and out: output paths, connection strings, ports in use, our ids,
file permissions. Each is one line and exit 2, before any work starts."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from support.paths import DATA

from gcs_planner.cli import main
from gcs_planner.errors import InputError
from gcs_planner.link.connection import check_connection
from gcs_planner.runtime.atomic import write_atomic

WORKBOOK = DATA / "dataset1.xlsx"
FLAGS = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
         "--delta", "0.001"]  # fmt: skip
UNWRITABLE = "/proc/gcs-planner-test/out"  # /proc refuses new files, even to root


def _one_line_error(capsys: pytest.CaptureFixture[str], *words: str) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    for word in words:
        assert word in err, err
    return err


@pytest.mark.parametrize("umask", [0o022, 0o027, 0o002])
def test_written_files_follow_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        path = write_atomic(tmp_path / "f.txt", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~umask


def _no_search(*args, **kwargs):
    raise AssertionError("the scenario was read although --out could never be written")


@pytest.mark.parametrize("kind", ["file", "unwritable"])
def test_plan_out_is_checked_before_the_search(tmp_path, capsys, monkeypatch, kind):
    monkeypatch.setattr("gcs_planner.cli.plan.load_scenario_from_args", _no_search)
    if kind == "file":
        out = tmp_path / "a-file"
        out.write_text("keep me")
    else:
        out = Path(UNWRITABLE)
    assert main(["plan", str(WORKBOOK), "--out", str(out)]) == 2
    _one_line_error(capsys, "--out", str(out))
    if kind == "file":
        assert out.read_text() == "keep me"


@pytest.mark.parametrize("kind", ["folder", "unwritable"])
def test_export_out_is_checked_before_the_plan_is_read(tmp_path, capsys, kind):
    out = tmp_path if kind == "folder" else Path(UNWRITABLE)
    plan = tmp_path / "no-such-plan.json"  # would be another error if it were read first
    assert main(["export", str(plan), "--format", "waypoints", "--out", str(out)]) == 2
    _one_line_error(capsys, "--out", "is a folder" if kind == "folder" else "cannot write")


def test_download_to_an_unwritable_place_is_bad_input_before_connecting(capsys):
    conn = ["--connect", f"udpout:127.0.0.1:{free_udp_port()}", "--wait", "30", "--quiet"]
    # No vehicle listens: a check made after connecting would wait 30 s and exit 4.
    assert main(["download", *conn, "--out", UNWRITABLE + ".json"]) == 2
    _one_line_error(capsys, "cannot write")


def test_download_onto_a_folder_is_bad_input_before_connecting(tmp_path, capsys):
    folder = tmp_path / "x.json"
    folder.mkdir()
    conn = ["--connect", f"udpout:127.0.0.1:{free_udp_port()}", "--wait", "30", "--quiet"]
    assert main(["download", *conn, "--out", str(folder)]) == 2
    _one_line_error(capsys, "is a folder")


@pytest.mark.parametrize(
    "conn, words",
    [
        ("foo:bar", ["not a connection"]),
        ("udpin:127.0.0.1:99999", ["99999", "1..65535"]),
        ("udpout:127.0.0.1", ["HOST:PORT"]),
        ("tcp::5760", ["HOST:PORT"]),
        ("/dev/ttyNO-SUCH-RADIO", ["cannot open"]),
    ],
)
def test_bad_connection_strings_are_bad_input(tmp_path, capsys, conn, words):
    plan = tmp_path / "m.waypoints"
    plan.write_text("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t30.5\t123.5\t10\t1\n")
    assert main(["upload", str(plan), "--connect", conn, "--wait", "1", "--quiet"]) == 2
    _one_line_error(capsys, "--connect", *words)
    scenario = ["--scenario", str(WORKBOOK), *FLAGS]
    assert main(["mock-vehicle", "--connect", conn, *scenario]) == 2
    _one_line_error(capsys, *words)


def test_connection_forms_that_pass():
    for conn in ("udpin:0.0.0.0:14550", "udpout:10.0.0.2:14550", "tcp:localhost:5760", "COM3",
                 "/dev/ttyUSB0"):  # fmt: skip
        assert check_connection(conn) == conn
    with pytest.raises(InputError):
        check_connection("udpin:0.0.0.0:0")


def test_a_second_vehicle_on_a_port_in_use_is_refused(capsys):
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}"):
        with pytest.raises(InputError, match="already using it"):
            MockVehicle(f"udpin:127.0.0.1:{port}")
        conn = f"udpin:127.0.0.1:{port}"
        code = main(["mock-vehicle", "--connect", conn, "--scenario", str(WORKBOOK), *FLAGS])
        assert code == 2
        _one_line_error(capsys, str(port), "already using it")


def test_source_system_and_component_are_ours_to_choose(tmp_path, capsys):
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4") as vehicle:
        out = tmp_path / "m.json"
        args = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet", "--out", str(out)]
        assert main(["download", *args, "--source-system", "7", "--source-component", "42"]) == 0
        assert (7, 42) in vehicle._peers
    with pytest.raises(SystemExit) as exit_:
        main(["download", *args, "--source-system", "0"])
    assert exit_.value.code == 2
    assert "argument --source-system: expected 1..255, got 0" in capsys.readouterr().err
