"""Every shell command the documentation shows runs, as written, and exits as the text says.

The commands are those of the fenced ```sh blocks of README.md, docs/*.md and
missions/README.md (a line continued with a backslash is one command; comment lines are
skipped). Each runs in bash, in a temporary copy of the repository's layout where `missions/...`,
`../shared/...` and `python -m benchmarks` resolve and `out/...` lands in the copy, never in the
repository. A command exits 0 unless its line ends in a comment `# exit N`. A block that starts
a background job (`... &`, a mock vehicle or a Dask cluster) runs as one bash script, each
command checked in turn. A command that reads `out/X` first runs the documented command that
writes it (README's first command writes `out/coast`), so each test stands alone and any order
works, on any xdist worker. Each command (or block) runs once in a test run, in the first test
process that needs it; the others take its exit code, output and `out/...` folders
(tests/support/shared_commands.py). Ids are `file:line`, so a failure names the documentation's
line.

What is not run as written is said here, each with its reason:

- the set-up commands (`python3 -m venv .venv && . .venv/bin/activate && pip install ... &&
  REST`): this test runs in an environment already installed with `.[test]`; it checks that the
  install's modules are there and runs REST in it (`SETUP`, `INSTALLED`);
- the suite's own command (`EXCLUDED`): it is the suite that runs this test;
- long runs are capped by GCS_PLANNER_DOCS_RUNS (default 5, set here when unset): `--runs N`
  becomes `--runs min(N, cap)`, and the sweep example's `[dry_run] runs` the same; its generated
  scenarios (`seeds = { count = N }`) are capped by GCS_PLANNER_DOCS_SEEDS (default 1), in the
  copy's `missions/sweep-example.toml`; the full benchmark run (about 20 minutes) runs its
  start-up section, `--startup --runs 1 --warm-cache` (`REWRITES`);
- the loopback ports (14550 for MAVLink, 8786 for Dask) become free ones, so that two workers
  or another test's vehicle do not collide;
- a command that fails by a product bug known and reported is a strict xfail
  (`KNOWN_PRODUCT_BUGS`): it fails the test as soon as it passes, so the entry is removed with
  the fix.

Blocks of other languages (`text`, `toml`, `json`, `python`) are not run here; README's Python
example and missions/README.md's files are tests/docs/test_docs.py's.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import socket
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from support.paths import REPO, SHARED, TESTS
from support.shared_commands import run_once

DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md")), REPO / "missions" / "README.md"]
RUNS = int(os.environ.setdefault("GCS_PLANNER_DOCS_RUNS", "5"))
SEEDS = int(os.environ.setdefault("GCS_PLANNER_DOCS_SEEDS", "1"))  # a sweep spec's seeds count
BIN = Path(sys.executable).parent  # the installed environment's scripts: gcs-planner, dask
TIMEOUT_S = 600  # a hang guard per command, not a measurement

SETUP = re.compile(
    r"^python3 -m venv \.venv && \. \.venv/bin/activate && pip install (?P<what>\S+)"
    r"(?: && (?P<rest>.+))?$"
)
PIP_ONLY = re.compile(r"^pip install (?P<what>\S+)$")
# What each documented install provides; the test environment must have it (installed '.[test]').
INSTALLED = {
    ".": ["gcs_planner"],
    "'.[test]'": [
        "pytest",
        "xdist",
        "hypothesis",
        "pymoo",
        "dask.distributed",
        "dask_jobqueue",
        "jsbsim",
    ],
    "'.[sweep]'": ["dask.distributed", "pyarrow", "bokeh"],
}
# The suite's own command: this test is part of what it runs.
EXCLUDED = {
    "python -m pytest -q -n 4": "the test suite itself, which is running this test; run from "
    "inside it, it would run this test again, and so on",
}
REWRITES = [
    # (what, why) - applied by rewrite() below, in this order
    ("--runs N -> --runs min(N, GCS_PLANNER_DOCS_RUNS)", "a verdict of 200 flights takes minutes"),
    ("python -m benchmarks ... -> python -m benchmarks --startup --runs 1 --warm-cache",
     "the full run takes about 20 minutes, --quick one or two; the start-up section seconds "
     "from the cache as it is (from a fresh one, as the full run times it, a minute of compiling)"),
    ("ports 14550 (MAVLink), 8786 (Dask) -> free ones", "workers and other tests use loopback"),
]  # fmt: skip
# command -> the product bug it fails by (reported); empty when every command runs.
KNOWN_PRODUCT_BUGS: dict[str, str] = {}
EXIT = re.compile(r"#\s*exit\s+(\d+)\s*$")
OUT_ROOT = re.compile(r"\bout/([\w.-]+)")
WRITES = re.compile(r"(?:--[\w-]*out|mkdir -p)\s+out/([\w.-]+)")


@dataclass
class Command:
    doc: str  # path relative to the repository
    line: int  # the documentation's line of its first line
    text: str  # one command, or a whole block's script (background jobs)
    lines: list[tuple[int, str, int]] = field(default_factory=list)  # script: (line, cmd, exit)
    expect: int = 0

    @property
    def id(self) -> str:
        return f"{self.doc}:{self.line}"

    @property
    def script(self) -> bool:
        return bool(self.lines)

    def commands(self) -> list[str]:
        return [text for _, text, _ in self.lines] if self.script else [self.text]

    def writes(self) -> set[str]:
        if any("--resume" in c for c in self.commands()):
            return set()
        return {m for c in self.commands() for m in WRITES.findall(c)}

    def reads(self) -> set[str]:
        mentioned = {m for c in self.commands() for m in OUT_ROOT.findall(c)}
        return mentioned - self.writes()


def logical_lines(block: str, first: int) -> list[tuple[int, str]]:
    """(line number, command) of a block: continuations joined, comments and blanks skipped."""
    found, pending, start = [], "", 0
    for offset, raw in enumerate(block.splitlines()):
        text = raw.rstrip()
        if not pending:
            start = first + offset
            if not text.strip() or text.lstrip().startswith("#"):
                continue
        if text.endswith("\\"):
            pending += text[:-1].strip() + " "
            continue
        found.append((start, (pending + text.strip()).strip()))
        pending = ""
    assert not pending, f"line {start}: a continuation with nothing after it"
    return found


def strip_comment(command: str) -> str:
    return re.sub(r"\s+#.*$", "", command)


def documented_commands() -> list[Command]:
    commands = []
    for path in DOCS:
        doc = str(path.relative_to(REPO))
        text = path.read_text(encoding="utf-8")
        for m in re.finditer(r"^```sh\n(.*?)^```", text, re.S | re.M):
            first = text.count("\n", 0, m.start(1)) + 1
            found = logical_lines(m.group(1), first)
            expect = [int(e.group(1)) if (e := EXIT.search(c)) else 0 for _, c in found]
            if any(strip_comment(c).endswith("&") for _, c in found):
                lines = [(n, c, x) for (n, c), x in zip(found, expect, strict=True)]
                commands.append(Command(doc, first, m.group(1), lines))
            else:
                for (n, c), x in zip(found, expect, strict=True):
                    commands.append(Command(doc, n, c, expect=x))
    return commands


COMMANDS = documented_commands()


def free_port(kind: int) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def rewrite(command: str, ports: dict[str, str]) -> str:
    """The command as it runs here (REWRITES): runs capped, the benchmark short, free ports."""
    command = re.sub(r"--runs (\d+)", lambda m: f"--runs {min(int(m.group(1)), RUNS)}", command)
    short = "python -m benchmarks --startup --runs 1 --warm-cache"
    command = re.sub(r"^python -m benchmarks( .*)?$", short, command)
    for documented, free in ports.items():
        command = re.sub(rf"\b{documented}\b", free, command)
    return command


def free_ports() -> dict[str, str]:
    return {
        "14550": str(free_port(socket.SOCK_DGRAM)),  # MAVLink over UDP
        "8786": str(free_port(socket.SOCK_STREAM)),  # Dask's scheduler
    }


def as_script(command: Command) -> str:
    """A block with background jobs as one bash script: each command checked as it ends."""
    body, ports = ["trap 'kill $(jobs -p) 2>/dev/null' EXIT"], free_ports()
    for line, text, expect in command.lines:
        text = rewrite(text, ports)
        if strip_comment(text).endswith("&"):
            body.append(text)
            continue
        body += [
            text,
            f'rc=$?; if [ "$rc" -ne {expect} ]; then echo "{command.doc}:{line}: exit $rc, '
            f'the documentation says {expect}" >&2; exit 1; fi',
        ]
    return "\n".join([*body, "wait", ""])


@dataclass
class Workspace:
    """A copy of the repository's layout in a temporary folder; commands run in `repo`."""

    repo: Path
    done: dict[str, subprocess.CompletedProcess] = field(default_factory=dict)

    def env(self) -> dict[str, str]:
        env = dict(os.environ, MPLBACKEND="Agg", GCS_PLANNER_DOCS_RUNS=str(RUNS))
        env["PATH"] = f"{BIN}{os.pathsep}{env.get('PATH', '')}"
        return env

    def run(self, command: Command) -> subprocess.CompletedProcess:
        """Run `command` once in this workspace, after the commands that write what it reads."""
        command = runnable(command)
        # A block by its text, a command by its text as run: each runs once in the whole run
        # (tests/support/shared_commands.py), whichever test process needs it first.
        key = command.text if command.script else strip_comment(command.text)
        if key in self.done:
            return self.done[key]
        for root in sorted(command.reads()):
            producer = writer_of(root, command)
            done = self.run(producer)
            assert done.returncode == producer.expect, (
                f"{command.id} reads out/{root}, written by {producer.id}, which failed:\n"
                + report(producer, done)
            )
        self.done[key] = run_once(key, self.repo, command.writes(), lambda: self.bash(command))
        return self.done[key]

    def bash(self, command: Command) -> subprocess.CompletedProcess:
        script = as_script(command) if command.script else rewrite(command.text, free_ports())
        return subprocess.run(
            ["bash", "-c", script],
            cwd=self.repo,
            env=self.env(),
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
        )


def runnable(command: Command) -> Command:
    """A set-up command as it runs here: what follows the install, in the installed environment."""
    if not command.script and (setup := SETUP.match(command.text)) and setup["rest"]:
        return Command(command.doc, command.line, setup["rest"], expect=command.expect)
    return command


def writer_of(root: str, reader: Command) -> Command:
    for command in COMMANDS:
        if command is not reader and root in command.writes():
            return command
    raise AssertionError(f"{reader.id} reads out/{root}, which no documented command writes")


def report(command: Command, done: subprocess.CompletedProcess) -> str:
    return (
        f"{command.id}: exit {done.returncode}, the documentation says {command.expect}\n"
        f"$ {command.text}\n--- stdout (end)\n{done.stdout[-3000:]}\n"
        f"--- stderr (end)\n{done.stderr[-3000:]}"
    )


@pytest.fixture(scope="session")
def workspace(tmp_path_factory) -> Workspace:
    if not SHARED.is_dir():
        raise FileNotFoundError(f"{SHARED} not found: ../shared must be beside the repository")
    base = tmp_path_factory.mktemp("docs")
    (base / "shared").symlink_to(SHARED)
    repo = base / "repo"
    (repo / "missions").mkdir(parents=True)
    (repo / "benchmarks").symlink_to(REPO / "benchmarks")
    for entry in sorted((REPO / "missions").iterdir()):
        if entry.name != "sweep-example.toml":
            (repo / "missions" / entry.name).symlink_to(entry)
    spec = (REPO / "missions" / "sweep-example.toml").read_text(encoding="utf-8")
    capped = re.sub(r"(?m)^runs = (\d+)", lambda m: f"runs = {min(int(m[1]), RUNS)}", spec)
    capped = re.sub(r"count = (\d+)", lambda m: f"count = {min(int(m[1]), SEEDS)}", capped)
    (repo / "missions" / "sweep-example.toml").write_text(capped, encoding="utf-8")
    return Workspace(repo)


def params() -> list:
    out = []
    for command in COMMANDS:
        marks = []
        if command.text in KNOWN_PRODUCT_BUGS:
            marks.append(pytest.mark.xfail(strict=True, reason=KNOWN_PRODUCT_BUGS[command.text]))
        out.append(pytest.param(command, id=command.id, marks=marks))
    return out


def installed(what: str) -> None:
    assert what in INSTALLED, f"an install of {what} that this test does not know: add it"
    missing = [m for m in INSTALLED[what] if importlib.util.find_spec(m) is None]
    assert not missing, f"pip install {what} should provide {missing}: this environment lacks it"


@pytest.mark.parametrize("command", params())
def test_documented_command(command: Command, workspace: Workspace):
    if not command.script and (setup := SETUP.match(command.text)):
        # The environment running this test is the installed one; the rest runs in it.
        installed(setup["what"])
        assert shutil.which("gcs-planner", path=str(BIN)), "gcs-planner is not installed"
        if setup["rest"] in EXCLUDED:
            assert "pytest" in setup["rest"] and Path(__file__).resolve().is_relative_to(TESTS)
            return  # EXCLUDED says why: it is the suite running this test
    elif not command.script and (pip := PIP_ONLY.match(strip_comment(command.text))):
        installed(pip["what"])
        return
    done = workspace.run(command)
    assert done.returncode == (0 if command.script else command.expect), report(command, done)


def test_the_documentation_has_commands_and_no_placeholders():
    assert len(COMMANDS) >= 25
    for command in COMMANDS:
        for text in command.commands():
            text = strip_comment(text)
            assert not re.search(r"<[^>]*>|\.\.\.|\b(SCENARIO|WORKBOOK|CONN|FILE|DIR)\b", text), (
                f"{command.id}: a placeholder in an sh block; write a concrete command: {text}"
            )


def test_every_exception_is_still_documented():
    texts = [c for command in COMMANDS for c in command.commands()]
    for excluded in EXCLUDED:
        assert any(t.endswith(" && " + excluded) for t in texts), excluded
    for bug in KNOWN_PRODUCT_BUGS:
        assert bug in texts, f"{bug}: no longer documented; drop it from KNOWN_PRODUCT_BUGS"
