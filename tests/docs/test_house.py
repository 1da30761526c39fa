"""The layout's rules, read from the source itself (docs/architecture.md): no import cycle
between files, no module or function too big to read, the autopilot named only by its record,
a small top of the package, and no test importing another test."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest
from support.paths import REPO

from gcs_planner.aircraft.autopilot import AUTOPILOTS

PACKAGES = ("gcs_planner", "sim")
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 150
# The files that may hold the autopilots' names as strings: their records.
NAME_HOLDERS = {"gcs_planner/aircraft/autopilot.py"}
TOP_MODULES = {"__init__", "__main__", "library", "errors"}


# folder -> the package it installs as (pyproject's package-dir)
INSTALLED_AS = {"gcs_planner": "gcs_planner", "sim": "gcs_planner.sim"}


def _sources() -> Iterator[tuple[str, Path]]:
    for package in PACKAGES:
        for path in sorted((REPO / package).rglob("*.py")):
            parts = path.relative_to(REPO / package).with_suffix("").parts
            parts = parts[:-1] if parts[-1] == "__init__" else parts
            yield ".".join((INSTALLED_AS[package], *parts)), path


MODULES = dict(_sources())


def _imports(name: str, path: Path) -> set[str]:
    """The project's modules ``name`` imports, anywhere in the file (at the top, in functions,
    under TYPE_CHECKING): a cycle hidden behind a lazy import is still a cycle."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                stem = ".".join(parts[: len(parts) - node.level + 1])
                base = f"{stem}.{base}" if base else stem
            submodules = {f"{base}.{a.name}" for a in node.names} & MODULES.keys()
            found |= submodules or ({base} & MODULES.keys())
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names} & MODULES.keys()
    return found - {name}


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one file (Tarjan, iteratively)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in edges:
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
    return found


def test_the_cycle_finder_finds_a_cycle_and_nothing_else() -> None:
    edges = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}, "e": set()}
    assert _cycles(edges) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle_between_files() -> None:
    edges = {name: _imports(name, path) for name, path in MODULES.items()}
    assert sum(map(len, edges.values())) > 100  # the scan sees the project's imports
    assert _cycles(edges) == []


@pytest.mark.parametrize("package", PACKAGES)
def test_no_module_too_long_to_read(package: str) -> None:
    long = {
        str(p.relative_to(REPO)): n
        for name, p in MODULES.items()
        if p.relative_to(REPO).parts[0] == package
        and (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES
    }
    assert long == {}


@pytest.mark.parametrize("package", PACKAGES)
def test_no_function_too_long_to_read(package: str) -> None:
    long = {}
    for path in MODULES.values():
        if path.relative_to(REPO).parts[0] != package:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1  # type: ignore[operator]
                if lines > MAX_FUNCTION_LINES:
                    long[f"{path.relative_to(REPO)}:{node.name}"] = lines
    assert long == {}


def _name_strings(path: Path) -> list[int]:
    """Lines where a string constant is an autopilot's name (docstrings aside)."""
    tree = ast.parse(path.read_text())
    docstrings = {
        id(body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef)
        and (body := node.body)
        and isinstance(body[0], ast.Expr)
        and isinstance(body[0].value, ast.Constant)
    }
    return [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, str)
        and node.value.lower() in AUTOPILOTS
        and id(node) not in docstrings
    ]


def test_the_autopilot_is_named_only_by_its_record() -> None:
    holders = {
        str(p.relative_to(REPO)): lines for p in MODULES.values() if (lines := _name_strings(p))
    }
    assert set(holders) <= NAME_HOLDERS, {k: v for k, v in holders.items() if k not in NAME_HOLDERS}
    assert holders  # the scan sees the record's own names


def test_the_top_of_the_package_holds_only_its_entry_points() -> None:
    top = {p.stem for p in (REPO / "gcs_planner").glob("*.py")}
    assert top - TOP_MODULES == set() or len(top - TOP_MODULES) <= 4
    assert top >= TOP_MODULES


def test_the_distribution_installs_every_package_under_its_own_name() -> None:
    """pyproject lists every package folder, sim/ as gcs_planner.sim: nothing else is
    installed at the top of site-packages (``import sim`` fails outside the checkout)."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib
    config = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    assert config["package-dir"] == {"gcs_planner.sim": "sim"}
    folders = {
        ".".join(
            (
                INSTALLED_AS[p.relative_to(REPO).parts[0]],
                *p.parent.relative_to(REPO / p.relative_to(REPO).parts[0]).parts,
            )
        )
        for package in PACKAGES
        for p in (REPO / package).rglob("__init__.py")
    }
    assert set(config["packages"]) == folders
    assert all(name.split(".")[0] == "gcs_planner" for name in config["packages"])


def test_no_test_imports_another_test() -> None:
    tests = {p.stem for p in (REPO / "tests").rglob("test_*.py")}
    importing = {}
    for path in (REPO / "tests").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module.rpartition(".")[2]]
            elif isinstance(node, ast.Import):
                names = [a.name.rpartition(".")[2] for a in node.names]
            hits = [n for n in names if n in tests]
            if hits:
                importing[str(path.relative_to(REPO))] = hits
    assert importing == {}
