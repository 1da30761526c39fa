import importlib.machinery
import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

# The tests' folder on the path, so that a test in any folder under it imports ``support``.
sys.path.insert(0, str(Path(__file__).resolve().parent))


def _prefer_the_installed_package() -> None:
    """Import the installed gcs_planner, not the source tree beside the tests, when the install
    is a copy (CI's non-editable `pip install '.[test]'`).

    From the checkout's root `python -m pytest` (and pyproject's ``pythonpath``, for
    benchmarks/) put the source tree first on sys.path, while the tests' `gcs-planner` commands
    run the installed copy. numba caches each file's kernels by the file's path, so the two
    copies would each be compiled, once before the tests and again in them; and the tests would
    check in process a copy the commands do not run. With an editable install (a developer's)
    the installed package is the source tree and nothing changes."""
    root = str(Path(__file__).resolve().parents[1])
    elsewhere = [p for p in sys.path if p not in ("", ".") and Path(p).resolve() != Path(root)]
    spec = importlib.machinery.PathFinder.find_spec("gcs_planner", elsewhere)
    if spec is None or spec.origin is None:
        return
    if Path(spec.origin).resolve().parent.parent == Path(root) or "gcs_planner" in sys.modules:
        return
    # Only this name is taken from the install: its submodules follow its __path__, and the
    # rest of sys.path (benchmarks/, tests/support) is left as it is.
    package = importlib.util.module_from_spec(spec)
    sys.modules["gcs_planner"] = package
    assert spec.loader is not None
    spec.loader.exec_module(package)


_prefer_the_installed_package()

from support.paths import DATA  # noqa: E402 - found through the path set above


def pytest_configure(config: pytest.Config) -> None:
    """One folder per run for the reference fronts the test processes share
    (tests/support/shared_results.py): made by the first process (xdist's controller, before
    it starts the workers, who inherit it) and removed at its end, so no run reads another's."""
    if hasattr(config, "workerinput") or os.environ.get("GCS_PLANNER_TEST_RESULTS"):
        return
    folder = tempfile.mkdtemp(prefix="gcs-planner-test-results-")
    os.environ["GCS_PLANNER_TEST_RESULTS"] = folder
    config.add_cleanup(lambda: shutil.rmtree(folder, ignore_errors=True))


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """With test processes, the tests that mostly wait run first in half of them.

    The link, radio and mock-vehicle tests (marked ``waits``) spend their time on protocol
    timers: most of a run's waiting, little of its CPU. Left where they fall in the collection,
    they gathered in one or two processes and ended the run waiting on timers while a core sat
    idle. Dealt first to every process, they all waited at once and the cores idled at the
    start instead; spread between modules in every process, their waits often fell together.
    So half of the processes (two of README's four) start with them while the other half
    compute, and the run ends on tests that keep both cores busy (docs/benchmarks.md, "The
    test suite", has the runs).

    xdist's ``worksteal`` hands the collection out in contiguous shares (the first process
    N // n tests, the next (N - that) // (n - 1), and so on) and steals from the ends of the
    queues, so a share is its dealt waiting tests, then a run of the others in their collected
    order (a module's tests stay together, for its fixtures). The order is the same in every
    process, as xdist requires; it changes which process runs a test and when, never what a
    test does.
    """
    count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "0"))
    if count < 2 or not hasattr(config, "workerinput"):
        return
    waiting = [item for item in items if item.get_closest_marker("waits")]
    working = [item for item in items if not item.get_closest_marker("waits")]
    waiters = max(1, count // 2)
    order: list[pytest.Item] = []
    left, taken = len(items), 0
    for share in range(count):
        size = left // (count - share)
        left -= size
        dealt = waiting[share::waiters] if share < waiters else []
        rest = max(0, size - len(dealt))
        order += dealt + working[taken : taken + rest]
        taken += rest
    order += working[taken:]
    # Every test once: a mistake here must not drop a test unseen.
    assert sorted(map(id, order)) == sorted(map(id, items)), "the reordering lost a test"
    items[:] = order


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
    # In three processes side by side (numba compiles on one core): the search here; the
    # straight legs and the flight in another interpreter importing the same copy of the
    # package; the cost-to-go tables of maps of 3,000+ points (the part "bounds") in a third.
    # Left to the tests that need them, those tables were compiled by whichever came first:
    # when the benchmark's quick run did, each of its planning subprocesses compiled them at
    # once (docs/benchmarks.md, "The test suite").
    import gcs_planner

    root = Path(gcs_planner.__file__).resolve().parents[1]
    beside = [
        subprocess.Popen(
            [sys.executable, "-c", _COMPILE_PARTS.format(parts=parts)],
            cwd=root,
            stdout=subprocess.DEVNULL,
        )
        for parts in (("straight", "flight"), ("bounds",))
    ]
    try:
        compile_kernels(say=lambda text: None, parts=("search",))
    except Exception as exc:  # noqa: BLE001 - the tests that need a kernel compile it and fail
        say(f"compiling the kernels before the tests failed ({exc}); each process compiles them")
    if any([process.wait() != 0 for process in beside]):  # a list: wait for every one
        say("compiling some of the kernels before the tests failed; each process compiles them")


_COMPILE_PARTS = (
    "from gcs_planner.runtime.precompile import compile_kernels\n"
    "compile_kernels(say=lambda text: None, parts={parts!r})\n"
)


@pytest.fixture(scope="session")
def dataset_paths() -> dict[int, Path]:
    paths = {1: DATA / "dataset1.xlsx", 2: DATA / "dataset2.xlsx"}
    missing = [str(p) for p in paths.values() if not p.exists()]
    if missing:  # CI clones the repo with ../shared beside it; without it this is a setup error
        raise FileNotFoundError(
            f"contest workbooks not found: {missing}; ../shared must be beside the repo"
        )
    return paths
