"""The notice before numba compiles the search kernels (issue 28): on a terminal only, only when
a kernel is not cached, one line, and the check itself loads no numba."""

from __future__ import annotations

import importlib.util
import json
import os
import pickle
import pty
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from support.scenarios import write_scenario_csv

from gcs_planner.runtime import compile_notice
from gcs_planner.scenario.generate import DATASET1, random_scenario

ENTRY = Path(sys.executable).parent / "gcs-planner"
PARAMS = [
    "--alpha1", "25", "--alpha2", "15", "--beta1", "20", "--beta2", "25", "--theta", "30",
    "--delta", "0.001", "--turn-radius", "200",
]  # fmt: skip
NOTICE = "compiling its kernels once (numba),"


def small_scenario(path: Path) -> Path:
    # 2,000 points whose proof takes about 600 labels, past the TRIAL (300) after which the
    # planner compiles its kernels (seed 3 is proven in 189 labels in Python: nothing compiles).
    return write_scenario_csv(random_scenario(2000, 2, params=DATASET1), path)


def run_on_terminal(args: list[str], env: dict[str, str]) -> tuple[int, str, str]:
    """Run with stderr on a pseudo-terminal (stdout a pipe); (exit status, stderr's text,
    stdout's)."""
    main, secondary = pty.openpty()
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=secondary, env=env)
    os.close(secondary)
    chunks = []
    while True:
        try:
            data = os.read(main, 4096)
        except OSError:  # EIO: the child closed its end
            break
        if not data:
            break
        chunks.append(data)
    os.close(main)
    assert proc.stdout is not None
    out = proc.stdout.read().decode("utf-8", "replace")
    return proc.wait(timeout=600), b"".join(chunks).decode("utf-8", "replace"), out


def _kernel_folders() -> list[Path]:
    """The folders of the kernels' sources as `gcs-planner` imports them (numba caches each
    file's kernels by its path): the tests import the same copy of the package as the command
    does, the installed one where it is a copy (tests/conftest.py)."""
    modules = {module for module, _ in compile_notice.KERNELS}
    return sorted({Path(importlib.util.find_spec(m).origin).parent for m in modules})


def _copy_cache_but(stem: str, cache: Path) -> None:
    """Copy the warm cache's entries (numba's index and data files) of every kernel source into
    ``cache`` (a NUMBA_CACHE_DIR of its own), all but those of the source file ``stem``."""
    for folder in _kernel_folders():
        # Where numba keeps them now: the first of its folders that holds any (NUMBA_CACHE_DIR,
        # else the source's __pycache__ before the user-wide cache, whose older entries numba
        # does not read then), and the sub-folder it looks in under the new NUMBA_CACHE_DIR.
        target = cache / _sub_folder(folder)
        for entry in _warm_entries(folder):
            if not entry.name.startswith(stem + "."):
                target.mkdir(parents=True, exist_ok=True)
                shutil.copy2(entry, target / entry.name)


def _sub_folder(folder: Path) -> str:
    """The sub-folder numba keeps ``folder``'s kernels in under a NUMBA_CACHE_DIR: the last of
    its folders is one (NUMBA_CACHE_DIR's or the user-wide cache's)."""
    return compile_notice._cache_dirs(folder / "x.py")[-1].name


def _warm_entries(folder: Path) -> list[Path]:
    """numba's cache files (index and data) for the kernel sources in ``folder``, from the
    folder numba reads them from."""
    for found in compile_notice._cache_dirs(folder / "x.py"):
        entries = sorted(found.glob("*.nb[ic]"))
        if entries:
            return entries
    return []


@pytest.fixture(scope="module")
def compiled(tmp_path_factory: pytest.TempPathFactory) -> str:
    """`gcs-planner compile` in the session's own cache (the default NUMBA_CACHE_DIR, which the
    tests' session start fills with -n): it says what was missing, compiles it, and ends with
    every kernel cached. Its stdout."""
    assert ENTRY.exists(), f"{ENTRY} missing: install the package (pip install -e .)"
    done = subprocess.run(
        [str(ENTRY), "compile"],
        cwd=tmp_path_factory.mktemp("compile"),
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("not compiled yet: "), done.stdout
    assert "every kernel is in numba's cache" in done.stdout, done.stdout
    return done.stdout


def test_a_fresh_cache_gets_one_notice_on_a_terminal(tmp_path: Path, compiled: str) -> None:
    """The one test that compiles a kernel on purpose, the smallest: NUMBA_CACHE_DIR a folder
    of its own holding every kernel but the airplane legs' (copied from the warm cache), stderr
    a terminal; the plan compiles that one, says so once, first, and is proven as every later
    one (its time limit does not count the compile: tests/runtime/test_work_clock.py)."""
    scenario = small_scenario(tmp_path / "points.csv")
    cache = tmp_path / "numba-cache"
    _copy_cache_but("airplane_kernel", cache)
    before = {p.name for p in cache.rglob("*.nbi")}
    assert any(n.startswith("search_kernel.search-") for n in before), before
    # (GCS_PLANNER_COMPILE=always: compiled at once, not planned in Python first; see
    # tests/runtime/test_first_run.py for the default.)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "GCS_PLANNER_COMPILE": "always"}
    # The default time limit (60 s of work, the compile not counted): a fixed 10 s was missed
    # by the search itself on a machine busy with four processes on two cores.
    args = [str(ENTRY), "plan", str(scenario), *PARAMS]
    code, err, out = run_on_terminal(args, env)
    assert code == 0, err
    assert "optimality: exact" in out, out
    # The run must have compiled (numba wrote the missing kernel's index), or a missing notice
    # proves nothing.
    new = {p.name for p in cache.rglob("*.nbi")} - before
    assert any(n.startswith("airplane_kernel.airplane_lengths-") for n in new), new
    assert err.count(NOTICE) == 1, err
    # The notice comes first, a line of its own, before any progress display.
    assert err.lstrip().startswith("gcs-planner: " + NOTICE), err


def test_after_compile_a_dry_run_compiles_nothing(tmp_path: Path, compiled: str) -> None:
    """After `gcs-planner compile` (every kernel the commands use, search and flight), a dry
    run (plan, upload, the vehicle's flight, the replay) compiles nothing (issue 54), in the
    same cache."""
    names = {p.name for folder in _kernel_folders() for p in _warm_entries(folder)}
    kernels = ("search_kernel.search-", "probe_kernel.probe-", "kernel.fewest_corrections-",
               "cost_to_go_kernel.merge_frontier-")  # fmt: skip
    for kernel in kernels:
        assert any(n.startswith(kernel) for n in names), (kernel, sorted(names))
    # A later process finds nothing left to compile (what a second `gcs-planner compile` says
    # as "none (all cached)"), read without loading numba.
    code = "from gcs_planner.runtime.precompile import missing; print(missing())"
    left = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True
    )
    assert left.stdout.strip() == "[]", left.stdout
    compiled_now = compiles_of([*DRY_RUN, str(EXAMPLE), "--quiet"], dict(os.environ), tmp_path)
    assert compiled_now == [], compiled_now


EXAMPLE = Path(__file__).resolve().parents[2] / "missions" / "example" / "scenario.toml"
DRY_RUN = ["dry-run"]
# Runs the command line in-process and lists numba's compiles of the project's kernels. The
# object-mode block of the search's progress tick (its arguments all ``ffi_forced_object``) is
# lifted and compiled in every process: numba caches no object-mode code, so it is not counted.
_COUNT = """
import json, sys
from numba.core import event
seen = []
class Listener(event.Listener):
    def on_start(self, ev):
        data = ev.data or {}
        f = getattr(data.get("dispatcher"), "py_func", None)
        module = getattr(f, "__module__", "") or ""
        lifted = all(str(a) == "ffi_forced_object" for a in data.get("args") or ())
        if module.startswith(("gcs_planner.", "sim.")) and not lifted:
            seen.append(module + "." + f.__name__)
    def on_end(self, ev):
        pass
event.register("numba:compile", Listener())
from gcs_planner.cli import main
code = main(sys.argv[1:])
print(json.dumps(seen))
sys.exit(code)
"""


def compiles_of(args: list[str], env: dict[str, str], cwd: Path) -> list[str]:
    """The project's kernels numba compiled while ``gcs-planner ARGS`` ran (stdout's last line)."""
    # Run outside the checkout: `python -c` puts the working folder first on sys.path, and from
    # the checkout's root it would import the source tree where `gcs-planner compile` imported
    # the installed package (a non-editable install: CI's), whose kernels numba caches apart.
    done = subprocess.run(
        [sys.executable, "-c", _COUNT, *args],
        env=env,
        capture_output=True,
        text=True,
        cwd=cwd,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_no_notice_off_a_terminal(tmp_path: Path) -> None:
    """A pipe gets nothing, even with an empty cache (logs and CI keep clean stderr)."""
    assert not compile_notice.maybe_notify(open(os.devnull, "w"))


class _Terminal:
    def __init__(self) -> None:
        self.text = ""

    def isatty(self) -> bool:
        return True

    def write(self, text: str) -> int:
        self.text += text
        return len(text)

    def flush(self) -> None:
        pass


def _fake_cache(folder: Path, version: str) -> None:
    """Index files for every kernel of the notice, as numba names them, written now."""
    import importlib.util

    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    for module, name in compile_notice.KERNELS:
        spec = importlib.util.find_spec(module)
        assert spec is not None and spec.origin is not None
        source = Path(spec.origin)
        sub = compile_notice._cache_dirs(source)[0]
        sub.mkdir(parents=True, exist_ok=True)
        with (sub / f"{source.stem}.{name}-10.{tag}.nbi").open("wb") as f:
            pickle.dump(version, f)
            f.write(b"rest of the index")
        os.utime(sub / f"{source.stem}.{name}-10.{tag}.nbi", (time.time() + 5, time.time() + 5))


def test_the_check_reads_numba_files_without_loading_numba(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import importlib.metadata

    version = importlib.metadata.version("numba")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "empty"))
    assert compile_notice.uncached_seconds() == sum(compile_notice.KERNELS.values())
    assert not compile_notice.maybe_notify(_Terminal(), quiet=True)
    # Written at the first compile of one of the package's kernels, once.
    stream = _Terminal()
    notice = compile_notice._Notice(stream, 30.0)

    class Event:
        def __init__(self, module: str) -> None:
            py_func = type("F", (), {"__module__": module})()
            self.data = {"dispatcher": type("D", (), {"py_func": py_func})()}

    notice.on_compile(Event("numpy.somewhere"))
    assert stream.text == ""
    notice.on_compile(Event("gcs_planner.core.probe_kernel"))
    notice.on_compile(Event("gcs_planner.core.search_kernel"))
    assert stream.text == f"gcs-planner: {NOTICE} about 30 s\n"
    assert "about 0 s" not in compile_notice.notice_text(0.4)
    # The dry run's flight kernels (sim/) announce it too.
    flight = compile_notice._Notice(_Terminal(), 14.0)
    flight.on_compile(Event("gcs_planner.sim.flight_kernel"))
    assert flight.stream.text == f"gcs-planner: {NOTICE} about 14 s\n"

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cached"))
    _fake_cache(tmp_path / "cached", version)
    assert compile_notice.uncached_seconds() == 0
    assert not compile_notice.maybe_notify(_Terminal())

    # Another numba's index is one numba ignores: compiled again, so the notice is due.
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "other"))
    _fake_cache(tmp_path / "other", "0.0.1")
    assert compile_notice.uncached_seconds() == sum(compile_notice.KERNELS.values())

    code = "import sys; from gcs_planner.runtime import compile_notice as c; c.uncached_seconds(); "
    code += "print('numba' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
