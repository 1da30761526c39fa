import subprocess
import sys
from pathlib import Path

import pytest

# The tests' folder on the path, so that a test in any folder under it imports ``support``.
sys.path.insert(0, str(Path(__file__).resolve().parent))

from support.paths import DATA  # noqa: E402 - found through the path set above


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session: pytest.Session) -> None:
    """With test processes (``-n``), compile numba's kernels once before they start.

    A fresh clone has no kernel in numba's cache, and each xdist worker would compile the same
    kernels at its first plan or flight, all of them at once (README's ``-n 4`` on two cores
    compiles each four times). Here the controller compiles them once, with the project's own
    ``gcs-planner compile`` (gcs_planner/runtime/precompile.py), before xdist starts the workers
    (its own sessionstart runs last); the workers load them from the cache. Nothing happens when
    every kernel is cached, in a worker, or without ``-n``. The fresh-cache tests of
    tests/runtime compile into caches of their own on purpose.
    """
    config = session.config
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return
    from gcs_planner.runtime.precompile import compile_kernels, missing

    if not missing():
        return
    terminal = config.pluginmanager.get_plugin("terminalreporter")
    say = terminal.write_line if terminal else (lambda text: None)
    say("numba's kernels are not cached: compiling them once for every test process ...")
    # The installed copy's too, beside this one's: from the checkout's root `python -m pytest`
    # imports the source tree, while the tests' `gcs-planner` commands run the installed package
    # (a non-editable install, as CI's), and numba caches each file's kernels by its path.
    installed = _installed_copy_elsewhere()
    other = None
    if installed is not None:
        entry = Path(sys.executable).with_name("gcs-planner")
        other = subprocess.Popen(
            [str(entry), "compile"], cwd=installed.parent.parent, stdout=subprocess.DEVNULL
        )
    try:
        compile_kernels(say=lambda text: None)
    except Exception as exc:  # noqa: BLE001 - the tests that need a kernel compile it and fail
        say(f"compiling the kernels before the tests failed ({exc}); each process compiles them")
    if other is not None and other.wait() != 0:
        say("compiling the installed package's kernels failed; its commands compile them")


def _installed_copy_elsewhere() -> Path | None:
    """The installed package's folder when it is not the one imported here (None for an
    editable install): asked of the interpreter outside the checkout, where the working folder
    on sys.path cannot shadow it."""
    import gcs_planner

    asked = subprocess.run(
        [sys.executable, "-c", "import gcs_planner; print(gcs_planner.__file__)"],
        cwd=Path(sys.executable).parent,
        capture_output=True,
        text=True,
    )
    if asked.returncode != 0:
        return None
    found = Path(asked.stdout.strip()).resolve()
    return found.parent if found != Path(gcs_planner.__file__).resolve() else None


@pytest.fixture(scope="session")
def dataset_paths() -> dict[int, Path]:
    paths = {1: DATA / "dataset1.xlsx", 2: DATA / "dataset2.xlsx"}
    missing = [str(p) for p in paths.values() if not p.exists()]
    if missing:  # CI clones the repo with ../shared beside it; without it this is a setup error
        raise FileNotFoundError(
            f"contest workbooks not found: {missing}; ../shared must be beside the repo"
        )
    return paths
