"""Bad input and write failures at the file edges (issue 29): a damaged plan.json, a write that
fails part-way, an output folder with something else in it, a negative mock-vehicle capacity,
absurd scenario coordinates. Each is exit 2 with one line naming the file (and row, field), no
traceback, and nothing half-written."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from support.missions import make_plan
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.cli import main
from gcs_planner.errors import InputError
from gcs_planner.mission import export as export_module
from gcs_planner.mission.builder import build_mission
from gcs_planner.mission.plan_json import load_plan
from gcs_planner.runtime.atomic import write_atomic, write_folder_atomic

ROWS = [("P0", 0, 0, "A"), ("P1", 12_000, 300, "V"), ("P2", 24_000, 0, "H"), ("P3", 36_000, 0, "B")]
FLAGS = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
         "--delta", "0.001", "--turn-radius", "0", "--origin", "30.5,123.5"]  # fmt: skip
OUT_FILES = sorted(export_module.ALL_FILES)


def one_line_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err, err
    assert err.startswith("gcs-planner")
    return err


@pytest.fixture
def scenario_csv(tmp_path: Path) -> Path:
    path = tmp_path / "line.csv"
    lines = ["id,x,y,z,kind,unreliable"] + [f"{i},{x},{y},500,{k},0" for i, x, y, k in ROWS]
    path.write_text("\n".join(lines) + "\n")
    return path


def run_cli(*args: str, preexec=None, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "gcs_planner", *args],
        capture_output=True,
        text=True,
        preexec_fn=preexec,
        cwd=cwd,
        timeout=300,
    )


# --- a damaged plan.json ---------------------------------------------------------------------


def damaged(tmp_path: Path, damage) -> Path:
    plan = make_plan()
    damage(plan)
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan))
    return path


@pytest.mark.parametrize(
    "damage, field",
    [
        (lambda p: p["scenario"].pop("origin"), "scenario.origin"),
        (lambda p: p.pop("scenario"), "scenario"),
        (lambda p: p["scenario"].update(origin_is_default=True), "scenario.origin_is_default"),
        (lambda p: p["scenario"].update(origin_is_default="no"), "scenario.origin_is_default"),
        (lambda p: p["scenario"].update(origin={"lat": 30.0}), "scenario.origin"),
        (lambda p: p["scenario"].update(origin={"lat": 95.0, "lon": 1.0}), "scenario.origin"),
        (lambda p: p.pop("parameters"), "parameters"),
        (lambda p: p["parameters"].pop("turn_radius"), "parameters.turn_radius"),
        (lambda p: p.update(chosen=True), "chosen"),
        (lambda p: p["front"][1].pop("legs"), "front[1].legs"),
        (lambda p: p["front"][0]["route"].__setitem__(1, "nowhere"), "front[0].route"),
    ],
)
def test_a_damaged_plan_json_is_refused_naming_the_field(tmp_path, capsys, damage, field):
    path = damaged(tmp_path, damage)
    with pytest.raises(InputError) as err:
        load_plan(path)
    assert err.value.field == field and err.value.file == str(path)
    out = tmp_path / "m.plan"
    assert main(["export", str(path), "--format", "plan", "--out", str(out)]) == 2
    message = one_line_error(capsys)
    assert str(path) in message and repr(field) in message
    assert not out.exists()


def test_a_plan_that_lost_its_origin_is_not_exported_to_the_default_one(tmp_path, capsys):
    """The issue's case: before, exit 0 and a mission 49 km from the landmarks."""
    path = damaged(tmp_path, lambda p: p["scenario"].pop("origin"))
    assert main(["export", str(path), "--format", "kml", "--out", str(tmp_path / "r.kml")]) == 2
    assert "lost its georeference" in one_line_error(capsys)
    # The upload path reads a plan JSON through the mission builder: the same refusal.
    with pytest.raises(InputError, match="lost its georeference"):
        build_mission(json.loads(path.read_text()), source=str(path))


def test_a_plan_without_an_origin_says_so_and_exports_at_the_default(
    tmp_path, scenario_csv, capsys, monkeypatch
):
    out = tmp_path / "out"
    leave_pictures_undrawn(monkeypatch)  # the origin is the subject here
    assert main(["plan", str(scenario_csv), *FLAGS[:-2], "--out", str(out)]) == 0  # no --origin
    data = json.loads((out / "plan.json").read_text())
    assert data["scenario"]["origin"] is None and data["scenario"]["origin_is_default"] is True
    capsys.readouterr()
    kml = str(tmp_path / "r.kml")
    assert main(["export", str(out / "plan.json"), "--format", "kml", "--out", kml]) == 0
    assert "default origin" in capsys.readouterr().err


# --- absurd coordinates, mock-vehicle flags ----------------------------------------------------


@pytest.mark.parametrize("cell, field", [("1e300", "x"), ("-3e7", "y"), ("inf", "x")])
def test_absurd_coordinates_are_refused_with_the_row(tmp_path, capsys, cell, field):
    path = tmp_path / "huge.csv"
    rows = ["id,x,y,z,kind,unreliable", "0,0,0,0,A,0", "1,5000,8000,1500,V,0", "2,1,1,1,B,0"]
    rows[2] = rows[2].replace("5000", cell) if field == "x" else rows[2].replace("8000", cell)
    path.write_text("\n".join(rows) + "\n")
    assert main(["plan", str(path), *FLAGS]) == 2
    message = one_line_error(capsys)
    assert f"{path}, row 3, field {field!r}" in message


def test_an_altitude_beyond_100_km_is_refused(tmp_path, capsys):
    path = tmp_path / "high.csv"
    path.write_text("id,x,y,z,kind,unreliable\n0,0,0,0,A,0\n1,10,10,2e5,B,0\n")
    assert main(["plan", str(path), *FLAGS]) == 2
    assert "row 3, field 'z'" in one_line_error(capsys)


# One refusal in a child process (the exit status and stderr a user sees), the other through
# the same entry point in this process (the child's imports are most of its CPU).
@pytest.mark.parametrize("flag, value, child", [("--capacity", "-1", True), ("--baud", "0", False)])
def test_mock_vehicle_refuses_a_negative_capacity(scenario_csv, capsys, flag, value, child):
    args = ["mock-vehicle", "--connect", "udpin:127.0.0.1:1", "--scenario", str(scenario_csv),
            *FLAGS, flag, value]  # fmt: skip
    if child:
        done = run_cli(*args)
        returncode, stderr = done.returncode, done.stderr
    else:
        with pytest.raises(SystemExit) as exited:
            main(args)
        returncode, stderr = exited.value.code, capsys.readouterr().err
    assert returncode == 2
    err = stderr.strip().splitlines()
    assert "Traceback" not in stderr and flag in err[-1]


# --- write failures ----------------------------------------------------------------------------


FILE_SIZE_LIMIT = 50_000  # bytes: under route.kml's and route.geojson's, over the 1 px PNGs


def _file_size_limit() -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_SIZE_LIMIT, FILE_SIZE_LIMIT))


@contextlib.contextmanager
def _soft_file_size_limit() -> Iterator[None]:
    """This process's file size limit lowered for the block (the soft one only, so that it can
    be raised back); Python ignores SIGXFSZ, so a write past it fails with EFBIG."""
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_SIZE_LIMIT, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs a POSIX child with its own limits")
def test_a_file_size_limit_is_one_line_and_leaves_nothing(
    tmp_path, scenario_csv, capsys, monkeypatch
):
    # plan --out (the folder), in this process: the pictures are not the subject (drawn, they
    # cost most of the CPU before the first write fails); route.kml and route.geojson exceed
    # the limit.
    leave_pictures_undrawn(monkeypatch)
    out = tmp_path / "out"
    with _soft_file_size_limit():
        rc = main(["plan", str(scenario_csv), *FLAGS, "--out", str(out)])
    assert rc == 2
    message = one_line_error(capsys)
    assert "File too large" in message and str(out) in message
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["line.csv"]  # no temporary folder left
    # One file (export), in a child process with its own limit: the signal the limit sends is
    # ignored there too, the same one line, exit 2, and no temporary file beside it. (KML, as
    # the PNG, is written through runtime/atomic.py write_atomic; it needs no matplotlib.)
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(make_plan()))
    kml = tmp_path / "route.kml"
    done = run_cli("export", str(plan), "--format", "kml", "--out", str(kml), "--allow-risky",
                   preexec=_file_size_limit)  # fmt: skip
    assert done.returncode == 2 and "Traceback" not in done.stderr
    last = done.stderr.strip().splitlines()[-1]
    assert "File too large" in last and str(kml) in last
    assert sorted(p.name for p in tmp_path.iterdir()) == ["line.csv", "plan.json"]


def test_a_folder_named_like_an_output_is_refused_before_planning(tmp_path, scenario_csv, capsys):
    out = tmp_path / "out"
    (out / "route.png").mkdir(parents=True)
    assert main(["plan", str(scenario_csv), *FLAGS, "--out", str(out)]) == 2
    message = one_line_error(capsys)
    assert "'route.png'" in message and str(out) in message
    assert [p.name for p in out.iterdir()] == ["route.png"]


def test_a_folder_with_the_users_own_files_is_never_replaced(tmp_path, scenario_csv, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main(["plan", str(scenario_csv), *FLAGS, "--out", str(out)]) == 2
    assert "'notes.txt'" in one_line_error(capsys)
    assert (out / "notes.txt").read_text() == "mine"


def test_write_atomic_reports_a_folder_in_the_way(tmp_path):
    (tmp_path / "route.png").mkdir()
    with pytest.raises(InputError) as err:
        write_atomic(tmp_path / "route.png", b"png")
    assert err.value.file == str(tmp_path / "route.png")
    assert [p.name for p in tmp_path.iterdir()] == ["route.png"]  # no temporary file


# --- plan --out is written as one folder ------------------------------------------------------


def test_plan_out_writes_every_file_and_replaces_an_earlier_run(
    tmp_path, scenario_csv, capsys, monkeypatch
):
    out = tmp_path / "out"
    assert main(["plan", str(scenario_csv), *FLAGS, "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == OUT_FILES
    mode = 0o777 & ~_umask()
    assert out.stat().st_mode & 0o777 == mode
    assert all(p.stat().st_mode & 0o777 == mode & 0o666 for p in out.iterdir())
    (out / "plan.json").write_text("stale")
    # The pictures were drawn above; the second run is about the folder it replaces.
    asked = leave_pictures_undrawn(monkeypatch)
    assert main(["plan", str(scenario_csv), *FLAGS, "--out", str(out)]) == 0
    assert sorted(asked) == ["error_budget_png", "front_png", "route_png"]
    assert json.loads((out / "plan.json").read_text())["format"] == "gcs-planner-plan"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["line.csv", "out"]


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


class Interrupted(KeyboardInterrupt):
    """A Ctrl-C part-way through the writing."""


def _interrupt_at_kml(monkeypatch) -> None:
    """Every writer before route.kml runs; route.kml's raises, as a Ctrl-C there would."""

    def boom(plan, mission):
        raise Interrupted

    name, _ = export_module.FORMATS["kml"]
    monkeypatch.setitem(export_module.FORMATS, "kml", (name, boom))


def test_an_interrupted_plan_out_leaves_no_folder(tmp_path, scenario_csv, monkeypatch, capsys):
    _interrupt_at_kml(monkeypatch)
    out = tmp_path / "out"
    assert main(["plan", str(scenario_csv), *FLAGS, "--out", str(out)]) == 130
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["line.csv"]


def test_an_interrupted_plan_out_leaves_the_previous_folder(
    tmp_path, scenario_csv, monkeypatch, capsys
):
    out = tmp_path / "out"
    leave_pictures_undrawn(monkeypatch)  # the folder left as it was is the subject here
    assert main(["plan", str(scenario_csv), *FLAGS, "--out", str(out)]) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    _interrupt_at_kml(monkeypatch)
    assert main(["plan", str(scenario_csv), *FLAGS, "--turn-radius", "100", "--out", str(out)])
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["line.csv", "out"]


def test_write_folder_atomic_restores_the_old_folder_when_the_swap_fails(tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_folder_atomic(out, [("a.txt", "old")])
    real_rename = os.rename
    calls = []

    def rename(src, dst):
        calls.append((Path(src).name, Path(dst).name))
        if len(calls) == 2:  # the new folder into place
            raise OSError(28, "No space left on device")
        real_rename(src, dst)

    monkeypatch.setattr(os, "rename", rename)
    with pytest.raises(InputError, match="No space left"):
        write_folder_atomic(out, [("a.txt", "new")])
    assert (out / "a.txt").read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out"]
