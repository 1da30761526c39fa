"""The documentation's snippets run: README's Python example and its commands (as the installed
`gcs-planner` script, in a subprocess), and every scenario file shown in missions/README.md."""

from __future__ import annotations

import functools
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from support.paths import REPO
from support.shared_commands import run_once
from support.undrawn_pictures import leave_pictures_undrawn

from gcs_planner.cli import main

SCRIPT = Path(sys.executable).parent / "gcs-planner"
DATASET1 = ["--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25",
            "--theta", "30", "--delta", "0.001"]  # fmt: skip


def blocks(path: Path, language: str) -> list[str]:
    """The fenced code blocks of ``language`` in a markdown file, in order."""
    return re.findall(rf"```{language}\n(.*?)```", path.read_text(encoding="utf-8"), re.S)


def in_repo_copy(tmp_path: Path, monkeypatch) -> Path:
    """A working directory where the README's relative paths resolve and outputs land in tmp."""
    (tmp_path / "missions").symlink_to(REPO / "missions")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def run_script(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(SCRIPT), *args], cwd=cwd, capture_output=True, text=True, timeout=600
    )


def test_readme_python_example_runs(tmp_path, monkeypatch):
    (code,) = [b for b in blocks(REPO / "README.md", "python") if "write_mission" in b]
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


def test_readme_first_command_plans_the_example_as_installed(tmp_path, monkeypatch):
    (setup,) = [b for b in blocks(REPO / "README.md", "sh") if "pip install . &&" in b]
    text = setup.strip().split(" && ")[-1]
    command = text.split()
    assert command[:2] == ["gcs-planner", "plan"]
    (tmp_path / "missions").symlink_to(REPO / "missions")
    written = command[command.index("--out") + 1]
    assert written.startswith("out/")
    # The installed script, run once in this test run: test_documented_commands.py's
    # README.md:13 runs the same command and shares its plan (tests/support/shared_commands.py).
    run = functools.partial(run_script, *command[1:], cwd=tmp_path)
    done = run_once(text, tmp_path, {written.removeprefix("out/")}, run)
    assert done.returncode == 0, done.stderr
    out = tmp_path / written
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
    (using,) = [b for b in blocks(REPO / "README.md", "sh") if "gcs-planner export" in b]
    (export,) = [line for line in using.splitlines() if line.startswith("gcs-planner export")]
    # In this process: README.md:106 of test_documented_commands.py runs it as installed.
    monkeypatch.chdir(tmp_path)
    assert main(export.split()[1:]) == 0
    assert (tmp_path / "mission.waypoints").read_text().startswith("QGC WPL 110")


def test_readme_dataset1_command_as_installed(tmp_path, dataset_paths):
    (using,) = [b for b in blocks(REPO / "README.md", "sh") if "the contest workbooks carry" in b]
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
    md = REPO / "missions" / "README.md"
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


def test_a_likely_lost_route_is_not_exported_unasked(tmp_path, capsys, monkeypatch):
    points = missions_snippets(tmp_path)["points.csv"]
    leave_pictures_undrawn(monkeypatch)  # the threshold is the subject here
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


# --- links, the model's sections, and nothing cited from outside the repository -------------

DOCS = [REPO / "README.md", REPO / "missions" / "README.md", *sorted((REPO / "docs").glob("*.md"))]
MODEL_DOC = REPO / "docs" / "model.md"
# Where the code and the documents cite the model (and where nothing may cite outside files).
CITING = ["gcs_planner", "sim", "tests", "missions", "docs", "benchmarks"]
# Built, not written out, so that a grep of the repository for them finds only what it should.
OUTSIDE = ("MODEL" + ".md", "../shared/" + "docs")
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def prose(path: Path) -> str:
    """A markdown file without its fenced code blocks (their '#' lines are no headings)."""
    return re.sub(r"^```.*?^```", "", path.read_text(encoding="utf-8"), flags=re.S | re.M)


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"[`*_]", "", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def headings(path: Path) -> list[str]:
    return [m.group(1).strip() for m in re.finditer(r"^#{1,6}\s+(.+)$", prose(path), re.M)]


def source_files() -> list[Path]:
    files = []
    for folder in CITING:
        for path in sorted((REPO / folder).rglob("*")):
            if path.suffix in (".py", ".md", ".toml") and "results" not in path.parts:
                files.append(path)
    return files


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: str(p.relative_to(REPO)))
def test_relative_links_resolve_inside_the_repository(doc):
    links = [t for t in LINK.findall(prose(doc)) if not re.match(r"[a-z]+:", t)]
    for target in links:
        file, _, anchor = target.partition("#")
        path = (doc.parent / file).resolve() if file else doc
        assert path.is_relative_to(REPO), f"{doc.name}: {target} leaves the repository"
        assert path.exists(), f"{doc.name}: {target} does not exist"
        if anchor and path.suffix == ".md":
            anchors = {slug(h) for h in headings(path)}
            assert anchor in anchors, f"{doc.name}: {target}: no heading #{anchor}"


def test_every_citation_of_the_model_names_one_of_its_sections():
    sections = headings(MODEL_DOC)
    names = {h.lower() for h in sections}
    cited = 0
    for path in source_files():
        text = path.read_text(encoding="utf-8")
        # The file, a comma and a quoted heading, across a line break and a comment marker too.
        for m in re.finditer(r'docs/model\.md,\s*(?:#\s*)?"([^"]+)"', text):
            name = " ".join(m.group(1).replace("#", " ").split())  # a name broken over lines
            assert name.lower() in names, f"{path.relative_to(REPO)} cites {name!r}"
            cited += 1
        for m in re.finditer(r"docs/model\.md,\s*(Table \d+)", text):
            assert any(m.group(1) in h for h in sections), f"{path.relative_to(REPO)}: {m[1]}"
            cited += 1
    assert cited >= 15  # the code does cite it: a broken pattern would pass vacuously


def test_the_model_has_the_sections_the_code_relies_on():
    names = set(headings(MODEL_DOC))
    for section in ("Scenario", "INS error model", "Objectives", "Leg geometry", "Airplane legs",
                    "Flight in the real world", "Uncertain corrections", "Contingency policies",
                    "Known figures"):  # fmt: skip
        assert section in names
    assert any(h.startswith("Table 2") for h in names)


def test_nothing_cites_a_document_outside_the_repository():
    for path in [*source_files(), REPO / "README.md"]:
        text = path.read_text(encoding="utf-8")
        for outside in OUTSIDE:
            assert outside not in text, f"{path.relative_to(REPO)} cites {outside}"


def test_readme_is_a_users_guide():
    text = (REPO / "README.md").read_text(encoding="utf-8")
    first_screen = "\n".join(text.splitlines()[:40])
    assert "GMCM" in first_screen and "../shared/data/gmcm2019f/" in first_screen
    found = headings(REPO / "README.md")
    for section in ("Set-up", "Planning", "Export", "Upload", "Dry run", "Library use",
                    "Scenario formats", "Exit codes", "Speed"):  # fmt: skip
        assert found.count(section) == 1, section
    # No lab notebook: commit hashes and "the run before" belong in CHANGELOG.md.
    commit = r"\b(?=[0-9a-f]*\d)(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}\b"
    assert not re.search(commit, prose(REPO / "README.md"))
    assert "run before" not in text and "this session" not in text
    # The benchmark's command and its main table stay in README.
    assert any("python -m benchmarks" in b for b in blocks(REPO / "README.md", "sh"))
    assert "| dataset 1 | " in text and "plain label search" in text
