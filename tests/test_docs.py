"""The documentation's snippets run: README's Python example and its commands (as the installed
`gcs-planner` script, in a subprocess), and every scenario file shown in missions/README.md."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from gcs_planner.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = Path(sys.executable).parent / "gcs-planner"
DATASET1 = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25",
            "--theta", "30", "--delta", "0.001"]  # fmt: skip


def blocks(path: Path, language: str) -> list[str]:
    """The fenced code blocks of ``language`` in a markdown file, in order."""
    return re.findall(rf"```{language}\n(.*?)```", path.read_text(encoding="utf-8"), re.S)


def in_repo_copy(tmp_path: Path, monkeypatch) -> Path:
    """A working directory where the README's relative paths resolve and outputs land in tmp."""
    (tmp_path / "missions").symlink_to(ROOT / "missions")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def run_script(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(SCRIPT), *args], cwd=cwd, capture_output=True, text=True, timeout=600
    )


def test_readme_python_example_runs(tmp_path, monkeypatch):
    (code,) = [b for b in blocks(ROOT / "README.md", "python") if "write_mission" in b]
    assert len([line for line in code.splitlines() if line.strip()]) <= 5 + 1  # + the import
    in_repo_copy(tmp_path, monkeypatch)
    namespace: dict = {}
    with pytest.warns(UserWarning, match="arrives with probability"):
        exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - the README's code
    written = sorted((tmp_path / "out").iterdir())
    assert [p.suffix for p in written] == [".plan"]
    mission = json.loads(written[0].read_text())
    assert mission["fileType"] == "Plan" and mission["mission"]["items"]
    shortest, result = namespace["shortest"], namespace["result"]
    # The shortest route at least 0.8 likely to arrive, from the same front.
    eligible = [r for r in result.front if r.probability >= 0.8 - 1e-12]
    assert shortest.route.length == min(r.length for r in eligible)
    assert result.route.probability >= 0.99 and result.threshold_met


def test_readme_first_command_plans_the_example_as_installed(tmp_path):
    (setup,) = [b for b in blocks(ROOT / "README.md", "sh") if "pip install . &&" in b]
    command = setup.strip().split(" && ")[-1].split()
    assert command[:2] == ["gcs-planner", "plan"]
    (tmp_path / "missions").symlink_to(ROOT / "missions")
    done = run_script(*command[1:], cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    out = tmp_path / command[command.index("--out") + 1]
    names = {p.name for p in out.iterdir()}
    assert {"mission.plan", "plan.json", "error_budget.png", "front.png", "route.png"} <= names
    plan = json.loads((out / "plan.json").read_text())
    assert len(plan["front"]) >= 3  # the example shows a choice worth making
    assert len({round(r["probability"], 6) for r in plan["front"]}) >= 2
    assert plan["front"][plan["chosen"]]["probability"] >= 0.99
    # ... and an aircraft limited to 15 degrees of climb flies some of its legs as helices.
    assert any(leg["helix_turns"] > 0 for r in plan["front"] for leg in r["legs"])
    assert "P lost" in done.stdout and "warning: no origin" not in done.stderr
    # README's export line reads that plan.json.
    (using,) = [b for b in blocks(ROOT / "README.md", "sh") if "gcs-planner export" in b]
    (export,) = [line for line in using.splitlines() if line.startswith("gcs-planner export")]
    done = run_script(*export.split()[1:], cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "mission.waypoints").read_text().startswith("QGC WPL 110")


def test_readme_dataset1_command_as_installed(tmp_path, dataset_paths):
    (using,) = [b for b in blocks(ROOT / "README.md", "sh") if "the contest workbooks carry" in b]
    first = using.split("\n# ")[0] if using.startswith("#") else using
    command = " ".join(line.rstrip("\\") for line in first.splitlines()[1:3]).split()
    assert command[:2] == ["gcs-planner", "plan"]
    command[2] = str(dataset_paths[1])
    done = run_script(*command[1:], "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    plan = json.loads(done.stdout)
    assert plan["min_probability"] == 0.99 and plan["threshold_met"]
    assert plan["front"][plan["chosen"]]["probability"] >= 0.99


def test_help_as_installed_lists_every_command(tmp_path):
    done = run_script("--help", cwd=tmp_path)
    assert done.returncode == 0
    for command in ("plan", "export", "upload", "download", "mock-vehicle", "dry-run"):
        assert command in done.stdout
    done = run_script("plan", "--help", cwd=tmp_path)
    assert "--min-probability" in done.stdout and "--allow-risky" in done.stdout


# --- missions/README.md ---------------------------------------------------------------------


def missions_snippets(tmp_path: Path) -> dict[str, Path]:
    md = ROOT / "missions" / "README.md"
    csvs = blocks(md, "csv")
    (geojson,) = blocks(md, "json")
    (toml,) = blocks(md, "toml")
    files = {"points.csv": csvs[0], "geo.csv": csvs[1], "points.geojson": geojson}
    files["scenario.toml"] = toml
    paths = {}
    for name, text in files.items():
        paths[name] = tmp_path / name
        paths[name].write_text(text, encoding="utf-8")
    return paths


@pytest.mark.parametrize("name", ["points.csv", "geo.csv", "points.geojson", "scenario.toml"])
def test_missions_readme_snippets_plan(tmp_path, capsys, name):
    path = missions_snippets(tmp_path)[name]
    flags = [] if name.endswith(".toml") else DATASET1
    assert main(["plan", str(path), *flags, "--json"]) == 0, capsys.readouterr().err
    plan = json.loads(capsys.readouterr().out)
    assert plan["front"] and plan["threshold_met"]


def test_points_snippets_plan_what_the_text_says(tmp_path, capsys):
    paths = missions_snippets(tmp_path)
    routes = []
    for name in ("points.csv", "geo.csv"):
        assert main(["plan", str(paths[name]), *DATASET1, "--json"]) == 0
        plan = json.loads(capsys.readouterr().out)
        routes.append([(r["route"], round(r["length"], 1)) for r in plan["front"]])
        chosen = plan["front"][plan["chosen"]]
        assert chosen["route"] == ["A", "V1", "H2", "V2", "B"] and chosen["probability"] == 1.0
    # The geographic copy is the same scenario to within the snippet's rounding.
    assert [r for r, _ in routes[0]] == [r for r, _ in routes[1]]
    for (_, a), (_, b) in zip(*routes, strict=True):
        assert a == pytest.approx(b, abs=1.0)


# --- the safe default: a likely-lost route is exported only when asked ----------------------


def test_a_likely_lost_route_is_not_exported_unasked(tmp_path, capsys):
    points = missions_snippets(tmp_path)["points.csv"]
    # With two objectives the front holds only the route through the unreliable H1 (P 0.8).
    two = [str(points), *DATASET1, "--objectives", "length,corrections"]
    out = tmp_path / "out"
    assert main(["plan", *two, "--out", str(out)]) == 3
    captured = capsys.readouterr()
    assert "most reliable one is chosen" in captured.out and "P lost" in captured.out
    assert "probability 0.8000" in captured.err and "--allow-risky" in captured.err
    assert not out.exists()

    for asked in (["--allow-risky"], ["--min-probability", "0.5"]):
        assert main(["plan", *two, "--out", str(out), *asked]) == 0
        err = capsys.readouterr().err
        assert "warning: route 0 arrives with probability 0.8000" in err
        assert (out / "mission.plan").exists()

    # export of that plan honours the plan's threshold (0.5 here) and a stricter one when given.
    plan_json = out / "plan.json"
    assert (
        main(["export", str(plan_json), "--format", "plan", "--out", str(tmp_path / "m.plan")]) == 0
    )
    capsys.readouterr()
    strict = ["--min-probability", "0.99", "--out", str(tmp_path / "n.plan")]
    assert main(["export", str(plan_json), "--format", "plan", *strict]) == 3
    assert not (tmp_path / "n.plan").exists()
