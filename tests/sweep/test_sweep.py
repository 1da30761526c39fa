"""The sweep's spec, cells and task, without a cluster: what a spec means, how a bad one is
reported, and what one cell's rows say."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import pytest
from support.paths import MISSIONS

from gcs_planner.aircraft.profile import turn_radius_from
from gcs_planner.cli import main
from gcs_planner.sweep import expand, read_spec, run_cell
from gcs_planner.sweep.spec import GeneratedSource

EXAMPLE_SPEC = MISSIONS / "sweep-example.toml"
EXAMPLE_SCENARIO = MISSIONS / "example" / "scenario.toml"


def write_spec(tmp_path: Path, text: str, name: str = "spec.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_example_spec_expands_scenarios_times_grid() -> None:
    spec = read_spec(EXAMPLE_SPEC)
    cells = expand(spec)
    # the example scenario and three generated ones, x 3 deltas x 2 radii
    assert len(spec.scenarios) == 4 and len(spec.value_sets) == 6 and len(cells) == 24
    assert spec.swept == ("delta", "turn_radius")
    assert len({c.key for c in cells}) == 24
    assert spec.scenarios[0].describe() == {"file": str(EXAMPLE_SCENARIO)}
    assert [s.seed for s in spec.scenarios[1:]] == [1, 2, 3]
    assert spec.dry_run_runs == 50


def test_cases_are_crossed_with_the_grid(tmp_path: Path) -> None:
    spec = read_spec(
        write_spec(
            tmp_path,
            f"""
[[scenarios]]
file = "{EXAMPLE_SCENARIO}"
[grid]
turn_radius = [0, 200]
objectives = [["length", "corrections"], "length,corrections,probability"]
[[cases]]
leg_model = "cs3d"
[[cases]]
delta = 0.0011
""",
        )
    )
    values = [dict(c.values) for c in expand(spec)]
    assert len(values) == 2 * 2 * 2
    assert {"leg_model": "cs3d", "turn_radius": 0.0, "objectives": ("length", "corrections")} in (
        values
    )
    assert {
        "delta": 0.0011,
        "turn_radius": 200.0,
        "objectives": ("length", "corrections", "probability"),
    } in values
    assert spec.swept == ("leg_model", "turn_radius", "objectives", "delta")


def test_cell_key_does_not_depend_on_the_order_of_cells(tmp_path: Path) -> None:
    a = write_spec(
        tmp_path,
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[grid]\ndelta = [1e-3, 2e-3]\n',
        "a.toml",
    )
    b = write_spec(
        tmp_path,
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[grid]\ndelta = [2e-3, 1e-3]\n',
        "b.toml",
    )
    ka = {dict(c.values)["delta"]: c.key for c in expand(read_spec(a))}
    kb = {dict(c.values)["delta"]: c.key for c in expand(read_spec(b))}
    assert ka == kb


BAD_SPECS = [
    # (spec text, what the one line must say)
    ('[[scenarios]]\nfile = "nope.toml"\n', "row 2, field 'scenarios[1].file'"),
    (
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n\n[grid]\ndelta = [0.001, "x"]\n',
        "row 5, field 'grid.delta': must be a finite number",
    ),
    (
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[grid]\nalpah1 = [1]\n',
        "row 4, field 'grid.alpah1': unknown key",
    ),
    (
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[grid]\np_success = [1.5]\n',
        "field 'grid.p_success': p_success must lie in [0, 1]",
    ),
    (
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[[scenarios]]\ngenerate = "random"\n'
        "corrections = 10\nseeds = [1, -2]\n",
        "row 6, field 'scenarios[2].seeds'",
    ),
    (
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[grid]\nleg_model = ["plane"]\n',
        "field 'grid.leg_model': unknown leg model 'plane'",
    ),
    (
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[plan]\nobjectives = ["length", "time"]\n',
        "row 4, field 'plan.objectives': unknown objective 'time'",
    ),
    (
        f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[dry_run]\nruns = 0\n',
        "row 4, field 'dry_run.runs'",
    ),
    ("name = 'x'\n", "field 'scenarios': no [[scenarios]]"),
    ("[[scenarios]\n", "row 1: TOML syntax error"),
]


@pytest.mark.parametrize(("text", "said"), BAD_SPECS)
def test_bad_spec_is_one_line_with_file_row_field_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture, text: str, said: str
) -> None:
    spec = write_spec(tmp_path, text)
    code = main(["sweep", str(spec), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"gcs-planner: error: {spec}, ")
    assert said in err
    assert not (tmp_path / "out").exists()


def test_without_dask_sweep_says_how_to_install_it(
    tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A None entry in sys.modules is how Python marks a module as not importable.
    monkeypatch.setitem(sys.modules, "distributed", None)
    code = main(["sweep", str(EXAMPLE_SPEC), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "sweep needs distributed" in err and "pip install 'gcs-planner[sweep]'" in err


def test_a_cell_whose_scenario_cannot_be_read_is_an_error_row(tmp_path: Path) -> None:
    points = tmp_path / "points.csv"
    points.write_text("id,x,y,z,kind,unreliable\n0,0,0,0,A,0\n1,5,5,oops,V,0\n2,9,9,9,B,0\n")
    scenario = tmp_path / "bad.toml"
    scenario.write_text(
        'points = "points.csv"\n[parameters]\nalpha1 = 25\nalpha2 = 15\nbeta1 = 20\n'
        "beta2 = 25\ntheta = 30\ndelta = 0.001\n"
    )
    spec = read_spec(write_spec(tmp_path, '[[scenarios]]\nfile = "bad.toml"\n'))
    (rows,) = [run_cell(c) for c in expand(spec)]
    assert len(rows) == 1
    assert rows[0]["status"] == "error"
    assert "InputError" in rows[0]["error"] and "row 3" in rows[0]["error"]


def test_generated_cell_applies_bank_angle_and_leg_model(tmp_path: Path) -> None:
    spec = read_spec(
        write_spec(
            tmp_path,
            '[[scenarios]]\ngenerate = "random"\ncorrections = 20\nseeds = [3]\n'
            "box = [40000, 20000, 2000]\n[grid]\ncruise_airspeed = 30\nmax_bank_angle = 40\n"
            'leg_model = "cs3d"\n[plan]\nobjectives = ["length", "corrections"]\n',
        )
    )
    (cell,) = expand(spec)
    assert isinstance(cell.source, GeneratedSource)
    rows = run_cell(cell)
    assert rows and all(r["status"] == "ok" for r in rows)
    assert rows[0]["turn_radius"] == pytest.approx(turn_radius_from(30.0, 40.0))
    assert rows[0]["leg_model"] == "cs3d" and rows[0]["cruise_airspeed"] == 30.0
    assert sum(r["chosen"] for r in rows) == 1


def test_out_that_is_a_file_is_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    out.write_text("not a folder")
    code = main(["sweep", str(EXAMPLE_SPEC), "--out", str(out)])
    err = capsys.readouterr().err
    assert (
        code == 2 and err == f"gcs-planner: error: {out}: is a file, not a folder for the results\n"
    )


def test_workers_below_one_is_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    code = main(["sweep", str(EXAMPLE_SPEC), "--out", str(tmp_path / "o"), "--workers", "0"])
    assert code == 2 and "field '--workers'" in capsys.readouterr().err


def test_reserve_reaches_generated_and_file_scenarios_and_the_table(tmp_path: Path) -> None:
    from gcs_planner.core.planner import plan
    from gcs_planner.scenario.generate import DATASET1, random_scenario

    spec = read_spec(
        write_spec(
            tmp_path,
            f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n'
            '[[scenarios]]\ngenerate = "random"\ncorrections = 20\nseeds = [3]\n'
            "box = [40000, 20000, 2000]\n[grid]\nreserve = [0, 3000]\n"
            '[plan]\nobjectives = ["length", "corrections"]\n',
        )
    )
    cells = expand(spec)
    rows = {(c.index, c.overrides["reserve"]): run_cell(c) for c in cells}
    for (_, reserve), cell_rows in rows.items():
        assert all(r["status"] == "ok" and r["reserve"] == reserve for r in cell_rows)
    # the generated cells plan with the reserve, as planning the scenario alone with it does
    generated = random_scenario(20, 3, params=DATASET1, box=(40000.0, 20000.0, 2000.0))
    for cell in cells[2:]:
        reserve = float(cell.overrides["reserve"])  # type: ignore[arg-type]
        alone = plan(generated.with_params(reserve=reserve), objectives=("length", "corrections"))
        got = sorted(rows[(cell.index, reserve)], key=lambda r: r["route"])
        assert [r["length"] for r in got] == pytest.approx([r.length for r in alone.routes])
    # and the reserve changes the plan: 3 km of the 15 km a component may fly is not nothing
    tight, loose = rows[(2, 0.0)], rows[(3, 3000.0)]
    assert [r["route_ids"] for r in tight] != [r["route_ids"] for r in loose]


def test_failed_cells_have_a_false_chosen_and_columns_carry_units(tmp_path: Path) -> None:
    import pyarrow.parquet as pq

    from gcs_planner.sweep.table import UNITS_CSV, ResultTable

    points = tmp_path / "points.csv"
    points.write_text("id,x,y,z,kind,unreliable\n0,0,0,0,A,0\n1,5,5,oops,V,0\n2,9,9,9,B,0\n")
    (tmp_path / "bad.toml").write_text(
        'points = "points.csv"\n[parameters]\nalpha1 = 25\nalpha2 = 15\nbeta1 = 20\n'
        "beta2 = 25\ntheta = 30\ndelta = 0.001\n"
    )
    spec = read_spec(
        write_spec(
            tmp_path,
            '[[scenarios]]\nfile = "bad.toml"\n'
            '[[scenarios]]\ngenerate = "random"\ncorrections = 20\nseeds = [3]\n'
            "box = [40000, 20000, 2000]\n[dry_run]\nruns = 5\n"
            '[plan]\nobjectives = ["length", "corrections"]\n',
        )
    )
    table = ResultTable.open(tmp_path / "out", resume=False)
    for cell in expand(spec):
        table.add(run_cell(cell))
    table.save()
    saved = pq.read_table(tmp_path / "out" / "results.parquet")
    assert saved.column("chosen").null_count == 0
    rows = saved.to_pylist()
    assert [r["chosen"] for r in rows if r["status"] == "error"] == [False]
    (chosen,) = [r for r in rows if r["chosen"]]
    # the level of the interval, as the dry run computed it
    from gcs_planner.core.planner import plan
    from gcs_planner.dryrun.run import dry_run
    from gcs_planner.sweep.task import load_cell_scenario

    cell = expand(spec)[1]
    report = dry_run(plan(load_cell_scenario(cell), objectives=("length", "corrections")),
                     load_cell_scenario(cell), runs=5, seed=0)  # fmt: skip
    assert chosen["dry_run_runs"] == 5 and 0 < report.confidence < 1
    assert chosen["dry_run_confidence"] == report.confidence
    assert (chosen["dry_run_ci_low"], chosen["dry_run_ci_high"]) == report.success_ci
    schema = saved.schema
    assert schema.field("reserve").metadata == {b"unit": b"m"}
    assert schema.field("length").metadata == {b"unit": b"m"}
    assert schema.field("cruise_airspeed").metadata == {b"unit": b"m/s"}
    units = (tmp_path / "out" / UNITS_CSV).read_text().splitlines()
    assert units[0] == "column,unit" and "turn_radius,m" in units and "plan_seconds,s" in units


def test_example_spec_plans_every_scenario_with_the_reserve_it_states(tmp_path: Path) -> None:
    spec = read_spec(EXAMPLE_SPEC)
    cells = expand(spec)
    # one file cell and one generated cell, without the dry run (the reserve is the plan's)
    for cell in (cells[0], cells[6]):
        rows = run_cell(replace(cell, dry_run_runs=0))
        assert rows and all(r["status"] == "ok" and r["reserve"] == 200.0 for r in rows)


def test_environment_and_search_settings_are_swept_and_columns(tmp_path: Path) -> None:
    import dataclasses

    from gcs_planner.core.planner import plan
    from gcs_planner.scenario.readers import load_scenario

    spec = read_spec(
        write_spec(
            tmp_path,
            f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n'
            "[grid]\ncapture_radius = [5, 400]\nerror_unit = 0.1\n"
            'choice = ["shortest", "fewest"]\n'
            "[[cases]]\nmax_labels = 50000\ntime_limit = 30\n"
            '[plan]\nobjectives = ["length", "corrections"]\nchoice = "compromise"\n',
        )
    )
    assert spec.swept == ("capture_radius", "choice")
    cells = expand(spec)
    assert len(cells) == 4
    base = load_scenario(EXAMPLE_SCENARIO)
    for cell in cells:
        values = dict(cell.values)
        rows = run_cell(cell)
        assert rows and all(r["status"] == "ok" for r in rows)
        assert all(
            r["capture_radius"] == values["capture_radius"] and r["error_unit"] == 0.1
            and r["choice"] == values["choice"] and r["max_labels"] == 50000
            and r["time_limit"] == 30.0
            for r in rows
        )  # fmt: skip
        # as planning the scenario alone with those values
        alone = plan(
            dataclasses.replace(base, capture_radius=values["capture_radius"], error_unit=0.1),
            objectives=("length", "corrections"),
            choice=values["choice"],
            max_labels=50000,
            time_limit=30,
        )
        got = sorted(rows, key=lambda r: r["route"])
        assert [r["route_ids"] for r in got] == [" ".join(r.ids()) for r in alone.routes]
        assert [r["chosen"] for r in got] == [i == alone.chosen for i in range(len(got))]
    assert len({c.key for c in cells}) == 4


def test_bad_swept_search_setting_names_the_field(tmp_path: Path) -> None:
    from gcs_planner.errors import InputError

    for text, said in (
        ('choice = ["nearest"]', "field 'grid.choice': unknown choice 'nearest'"),
        ("max_labels = [0.5]", "field 'grid.max_labels': must be a whole number >= 1"),
        ("capture_radius = [0]", "field 'grid.capture_radius': must be > 0"),
    ):
        path = write_spec(tmp_path, f'[[scenarios]]\nfile = "{EXAMPLE_SCENARIO}"\n[grid]\n{text}\n')
        with pytest.raises(InputError, match=said.replace("(", r"\(").replace(")", r"\)")):
            read_spec(path)


_ROWS_OF_CELLS = """
import json, sys
if sys.argv[2] == "numba-first":
    import numba  # as after an earlier cell whose search loaded it
from gcs_planner.sweep import expand, read_spec, run_cell
rows = [row for cell in expand(read_spec(sys.argv[1])) for row in run_cell(cell)]
when = ("plan_seconds", "cell_seconds", "worker", "finished_at")  # where and how long
print(json.dumps([{k: v for k, v in r.items() if k not in when} for r in rows], default=str))
"""


def test_a_cells_rows_do_not_depend_on_what_its_process_planned_before(tmp_path: Path) -> None:
    """Once numba is loaded a search flies its airplane legs compiled from the first label
    (core/bnb/search.py), a few ulp from numpy's, which moved lower bounds and gaps; a cell
    loads it itself before it plans, so a fresh worker, a reused one and the serial loop give
    the same rows to the last bit."""
    import json
    import subprocess

    spec = tmp_path / "spec.toml"
    spec.write_text(
        'name = "ulp"\n[[scenarios]]\ngenerate = "random"\ncorrections = 611\n'
        'seeds = { first = 1, count = 4 }\nparameters = "dataset1"\n'
        "[grid]\nturn_radius = [200]\n"
    )
    out = {}
    for mode in ("fresh", "numba-first"):
        done = subprocess.run(
            [sys.executable, "-c", _ROWS_OF_CELLS, str(spec), mode],
            capture_output=True, text=True, check=True, timeout=600,
        )  # fmt: skip
        out[mode] = json.loads(done.stdout)
    assert all(r["status"] == "ok" for r in out["fresh"]), out["fresh"]
    assert out["fresh"] == out["numba-first"]
