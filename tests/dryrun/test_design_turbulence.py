"""Plans for the air they will meet (gcs_planner/cli/dry_run.py, cli/plan.py, dryrun/air.py):
``dry-run --turbulence X`` plans for X, ``--design-turbulence Y`` flies a plan made for Y, and
``plan --turbulence`` records the design, each capture's allowance and the loop it assumed.

The short line (tests/support/short_line.py: A, V, B 12 km apart at 5,000 m, 25 m/s EAS) leaves
B 1.2 m of vertical and 2.4 m of horizontal error on arrival: with the 1.02 m tracking
allowance a vertical allowance of up to 1.97 m fits the 5 m capture radius, sigma_w 0.1 m/s
(1.36 m at TECS_TIME_CONST 5 s) does and 0.5 m/s (6.8 m) cannot."""

from __future__ import annotations

import json

import pytest
from support.short_line import short_line

from gcs_planner.cli import main


def _dry_run(path, *flags: str) -> tuple[int, dict | None]:  # noqa: ANN001
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        rc = main(["dry-run", str(path), *flags, "--json", "--quiet"])
    text = out.getvalue()
    return rc, (json.loads(text) if text.strip() else None)


def test_a_plan_for_the_turbulence_flown_keeps_every_capture(tmp_path, capsys):
    rc, d = _dry_run(short_line(tmp_path), "--turbulence", "0.1", "--runs", "20")
    assert rc == 0 and d["flight_losses"] == 0 and d["runs"] == 20
    assert "every capture fits" in capsys.readouterr().err


def test_the_dry_run_plans_for_the_turbulence_it_flies_and_refuses_what_cannot_fit(
    tmp_path, capsys
):
    path = short_line(tmp_path, '\n[environment]\nturbulence = "0.5"\n')
    rc, d = _dry_run(path, "--runs", "5")
    assert rc == 3 and d is None
    err = capsys.readouterr().err
    assert "no route fits its captures in the design turbulence" in err
    assert "B's vertical allowance 6.7" in err


def test_a_still_air_plan_flown_in_turbulence_is_caught(tmp_path):
    rc, d = _dry_run(
        short_line(tmp_path), "--design-turbulence", "0", "--turbulence", "2", "--runs", "10"
    )
    assert rc == 5 and d["flight_losses"] > 0 and not d["ok"]
    assert "vertical turbulence sigma_w 2" in d["wind"]


def test_a_bad_design_turbulence_names_its_flag(tmp_path, capsys):
    rc, _ = _dry_run(short_line(tmp_path), "--design-turbulence", "stormy")
    assert rc == 2
    assert "--design-turbulence" in capsys.readouterr().err


def test_the_plan_records_the_design_and_the_setup_holds_the_loop(tmp_path, capsys):
    path = short_line(tmp_path)
    assert main(["plan", str(path), "--turbulence", "0.1", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    t = d["capture"]["turbulence"]
    assert t["sigma_w_m_s"] == 0.1 and t["loop_param"] == "TECS_TIME_CONST"
    assert t["time_constant_s"] == 5.0 and t["k"] == pytest.approx(3.29, abs=0.01)
    assert set(t["points"]) == {"P1", "P2"}
    assert d["capture"]["first_not_captured"] is None
    loop = [p for p in d["setup"]["parameters"] if p["name"] == "TECS_TIME_CONST"]
    assert loop == [loop[0]] and loop[0]["most"] == 5.0 and loop[0]["value"] == 5.0
    assert main(["plan", str(path), "--json"]) == 0
    plain = json.loads(capsys.readouterr().out)
    assert "turbulence" not in plain["capture"]
    assert not [p for p in plain["setup"]["parameters"] if p["name"] == "TECS_TIME_CONST"]
