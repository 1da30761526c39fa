"""The library's face: `from gcs_planner import ...`, its policy shared with the command line, and
a light import (heavy libraries load only where they are used)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from support.paths import MISSIONS, REPO

import gcs_planner
from gcs_planner import (
    DEFAULT_MIN_PROBABILITY,
    InputError,
    Origin,
    RiskyRouteError,
    RiskyRouteWarning,
    choose,
    load_scenario,
    plan,
    write_mission,
)
from gcs_planner.cli import main
from gcs_planner.mission.qgc_plan import read_plan

COAST = MISSIONS / "coast" / "scenario.toml"
SNIPPET = "id,x,y,z,kind,unreliable\nA,0,0,1000,A,0\nV1,12000,800,1200,V,0\n" + (
    "H1,24000,-500,1500,H,1\nH2,23500,1500,1400,H,0\nV2,36000,0,1300,V,0\nB,48000,0,1100,B,0\n"
)
LIMITS = dict(alpha1=25, alpha2=15, beta1=20, beta2=25, theta=30, delta=0.001)


def test_every_public_name_resolves_and_is_documented():
    for name in gcs_planner.__all__:
        value = getattr(gcs_planner, name)
        if callable(value):
            assert value.__doc__, name
    with pytest.raises(AttributeError):
        gcs_planner.no_such_name  # noqa: B018


def test_library_and_command_line_make_the_same_choice(capsys):
    result = plan(load_scenario(COAST))
    assert main(["plan", str(COAST), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["objectives"] == list(result.objectives)
    assert "probability" in result.objectives  # the scenario has unreliable landmarks
    assert data["front"][data["chosen"]]["route"] == result.route.ids()
    assert result.min_probability == DEFAULT_MIN_PROBABILITY == data["min_probability"]


def test_choose_and_threshold_fallback():
    result = plan(load_scenario(COAST))
    by = {how: choose(result, how, min_probability=0.0) for how in ("shortest", "fewest")}
    assert by["shortest"].route.length == min(r.length for r in result.front)
    assert by["fewest"].route.corrections == min(r.corrections for r in result.front)
    assert all(c.front == result.front for c in by.values())  # the front is kept whole
    best = max(r.probability for r in result.front)
    worst = min(r.probability for r in result.front)
    assert worst < best
    # Asking for more than any route gives the most reliable one, and says so.
    none = choose(result, "shortest", min_probability=1.0)
    assert none.threshold_met == (best >= 1.0)
    assert none.route.probability == best


def test_load_scenario_overrides(tmp_path):
    points = tmp_path / "points.csv"
    points.write_text(SNIPPET)
    s = load_scenario(points, **LIMITS, turn_radius=0, origin=(30.5, 123.5))
    assert s.params.turn_radius == 0 and s.origin == Origin(30.5, 123.5, 0.0)
    with pytest.raises(TypeError, match="alpha_1"):
        load_scenario(points, alpha_1=3)
    with pytest.raises(InputError, match="delta"):
        load_scenario(points, **{**LIMITS, "delta": -1})


def test_write_mission_refuses_a_risky_route_unless_allowed(tmp_path):
    points = tmp_path / "points.csv"
    points.write_text(SNIPPET)
    scenario = load_scenario(points, **LIMITS, origin=(30.5, 123.5))
    result = plan(scenario, objectives=("length", "corrections"))
    assert not result.threshold_met and result.route.probability == pytest.approx(0.8)
    with pytest.raises(RiskyRouteError, match="0.8000"):
        write_mission(result, tmp_path / "m.plan")
    assert not (tmp_path / "m.plan").exists()
    with pytest.warns(RiskyRouteWarning, match="0.8000"):
        out = write_mission(
            result, tmp_path / "m.waypoints", allow_risky=True, firmware="ardupilot"
        )
    assert out.exists()
    safe = plan(scenario)  # with the probability objective the certain route is on the front
    assert safe.threshold_met and safe.route.probability == 1.0
    written = write_mission(safe, tmp_path / "safe.plan")
    assert len(read_plan(written).items) > len(safe.route.ids())
    with pytest.raises(InputError, match="file type"):
        write_mission(safe, tmp_path / "m.txt")


HEAVY = ("matplotlib", "pyproj", "openpyxl", "numba", "pymavlink", "mavsdk", "scipy.optimize")


def modules_after(code: str) -> set[str]:
    done = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys; print(' '.join(sys.modules))"],
        capture_output=True,
        text=True,
        check=True,
        cwd=REPO,
        timeout=600,
    )
    return set(done.stdout.splitlines()[-1].split())


def test_import_is_light():
    loaded = modules_after("import gcs_planner, gcs_planner.cli; gcs_planner.cli.build_parser([])")
    assert not {m for m in loaded if m.split(".")[0] in ("numpy", "scipy", *HEAVY)}


def test_plan_json_imports_only_what_it_uses():
    # A scenario in local metres: no projection (pyproj), no workbook (openpyxl), no picture.
    example = MISSIONS / "example" / "scenario.toml"
    code = (
        "import contextlib, io\nfrom gcs_planner.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        f"    assert main(['plan', {str(example)!r}, '--json']) == 0"
    )
    loaded = modules_after(code)
    assert "numpy" in loaded and "scipy.spatial" in loaded  # the search's own
    assert not {m for m in loaded for h in HEAVY if m == h or m.startswith(h + ".")}
