"""The notice before numba compiles the search kernels (issue 28): on a terminal only, only when
a kernel is not cached, one line, and the check itself loads no numba."""

from __future__ import annotations

import json
import os
import pickle
import pty
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
NOTICE = "compiling its kernels once (numba), about"


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


def test_a_fresh_cache_gets_one_notice_on_a_terminal(tmp_path: Path) -> None:
    """The one test that compiles: NUMBA_CACHE_DIR an empty folder, stderr a terminal; the
    first plan is proven as every later one (its time limit does not count the compile:
    tests/runtime/test_work_clock.py). Then `gcs-planner compile` in the same cache compiles
    what the plan did not need, and a second one finds nothing left: one compile of every kernel for
    both tests (each took a minute or more of CI alone)."""
    assert ENTRY.exists(), f"{ENTRY} missing: install the package (pip install -e .)"
    scenario = small_scenario(tmp_path / "points.csv")
    # (GCS_PLANNER_COMPILE=always: compiled at once, not planned in Python first; see
    # tests/runtime/test_first_run.py for the default.)
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(tmp_path / "numba-cache"),
        "GCS_PLANNER_COMPILE": "always",
    }
    # The default time limit (60 s of work, the compile not counted): a fixed 10 s was missed
    # by the search itself on a machine busy with four processes on two cores.
    args = [str(ENTRY), "plan", str(scenario), *PARAMS]
    code, err, out = run_on_terminal(args, env)
    assert code == 0, err
    assert "optimality: exact" in out, out
    # The run must have compiled (numba wrote its index files), or a missing notice proves nothing.
    compiled = list((tmp_path / "numba-cache").rglob("*.nbi"))
    assert compiled, "the plan compiled no kernel: pick a scenario that needs the compiled search"
    assert err.count(NOTICE) == 1, err
    # The notice comes first, a line of its own, before any progress display.
    assert err.lstrip().startswith("gcs-planner: " + NOTICE), err

    # `gcs-planner compile` fills the rest of the cache, and then has nothing left to do.
    env.pop("GCS_PLANNER_COMPILE")
    first = subprocess.run([str(ENTRY), "compile"], env=env, capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    assert "every kernel is in numba's cache" in first.stdout
    names = sorted(p.name for p in (tmp_path / "numba-cache").rglob("*.nbi"))
    for kernel in ("search_kernel.search-", "probe_kernel.probe-", "kernel.fewest_corrections-"):
        assert any(n.startswith(kernel) for n in names), (kernel, names)
    again = subprocess.run([str(ENTRY), "compile"], env=env, capture_output=True, text=True)
    assert again.returncode == 0 and "none (all cached)" in again.stdout, again.stdout

    # After `gcs-planner compile` a dry run (plan, upload, the vehicle's flight, the replay)
    # compiles nothing: the flight kernels are the compile's too (issue 54).
    compiled = compiles_of([*DRY_RUN, str(EXAMPLE), "--quiet"], env)
    assert compiled == [], compiled


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


def compiles_of(args: list[str], env: dict[str, str]) -> list[str]:
    """The project's kernels numba compiled while ``gcs-planner ARGS`` ran (stdout's last line)."""
    # Run outside the checkout: `python -c` puts the working folder first on sys.path, and from
    # the checkout's root it would import the source tree where `gcs-planner compile` imported
    # the installed package (a non-editable install: CI's), whose kernels numba caches apart.
    done = subprocess.run(
        [sys.executable, "-c", _COUNT, *args],
        env=env,
        capture_output=True,
        text=True,
        cwd=Path(env["NUMBA_CACHE_DIR"]).parent,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_no_notice_off_a_terminal(tmp_path: Path) -> None:
    """A pipe gets nothing, even with an empty cache (logs and CI keep clean stderr); the plan
    is the same small one, so this costs no compile when its cache is warm."""
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
    assert stream.text == f"gcs-planner: {NOTICE} 30 s\n"
    # The dry run's flight kernels (sim/) announce it too.
    flight = compile_notice._Notice(_Terminal(), 14.0)
    flight.on_compile(Event("gcs_planner.sim.flight_kernel"))
    assert flight.stream.text == f"gcs-planner: {NOTICE} 14 s\n"

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
