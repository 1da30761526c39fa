"""The one line a terminal gets before numba compiles the search kernels (issue 28).

With an empty numba cache (a fresh install, a new numba, edited kernel sources) the first plan
spends tens of seconds compiling before any progress can be shown, and a blank terminal looks
hung. Whether a kernel is cached is read from the files numba keeps, without importing numba
(the planner decides some paths by whether numba is loaded, and a small plan never loads it):
an index file ``<function>-<line>.py<XY>.nbi`` in one of the folders numba looks in, written by
this numba version (the index's first pickle) after the kernel's source last changed (numba
drops an index whose source stamp differs). Anything unreadable counts as cached: a missing
notice costs less than a false one on every run.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.abc
import importlib.metadata
import importlib.util
import os
import pickle
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, TextIO

from gcs_planner.runtime.terminal import on_terminal

# The kernels a command compiles at its first use, with the seconds of CPU their compiling is
# expected to take (from an empty cache, each with the kernels it calls; how they are measured:
# docs/benchmarks.md, "The first plan after installing"): the notice tells the user how long a
# first plan or dry run will be busy. A three-objective plan compiles the search (with the
# expansion it shares with the probes and the airplane legs), then the probes; a large
# straight plan fewest_corrections; any plan on 3,000+ points the cost-to-go tables; a plan
# flying a route the airplane legs alone.
KERNELS: dict[tuple[str, str], float] = {
    ("gcs_planner.core.probe_kernel", "probe"): 6.0,
    ("gcs_planner.core.kernel", "fewest_corrections"): 11.0,
    ("gcs_planner.core.cost_to_go_kernel", "merge_frontier"): 9.0,
    ("gcs_planner.geometry.airplane_kernel", "airplane_lengths"): 0.5,
    ("gcs_planner.core.search_kernel", "search"): 17.0,
    # The compiled flight of the dry run.
    ("gcs_planner.sim.flight_kernel", "fly_plain"): 12.0,
    ("gcs_planner.sim.flight_kernel", "closest_approach"): 2.0,
}


def _cache_dirs(source: Path) -> list[Path]:
    """The folders numba keeps ``source``'s cache in (numba.core.caching's locators): the
    user's NUMBA_CACHE_DIR, the source's own __pycache__, the user-wide cache."""
    folder = source.parent
    # numba's get_suitable_cache_subpath: the parent folder's name and a hash of its path.
    sub = f"{folder.name}_{hashlib.sha1(str(folder).encode()).hexdigest()}"
    dirs = []
    if os.environ.get("NUMBA_CACHE_DIR"):
        dirs.append(Path(os.environ["NUMBA_CACHE_DIR"]) / sub)
        return dirs  # numba then looks nowhere else
    dirs.append(folder / "__pycache__")
    dirs.append(Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "numba" / sub)
    return dirs


def _cached(module: str, name: str, numba_version: str) -> bool:
    spec = importlib.util.find_spec(module)
    if spec is None or spec.origin is None:
        return True
    source = Path(spec.origin)
    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    changed = source.stat().st_mtime
    for folder in _cache_dirs(source):
        for index in folder.glob(f"{source.stem}.{name}-*.{tag}.nbi"):
            try:
                with index.open("rb") as f:
                    version = pickle.load(f)  # a plain string: nothing of numba's is loaded
            except (OSError, pickle.UnpicklingError, EOFError, ValueError):
                continue
            if version == numba_version and index.stat().st_mtime >= changed:
                return True
    return False


def kernel_cached(module: str, name: str) -> bool:
    """Whether numba has ``module.name`` in its cache (True when that cannot be told: numba
    missing or its files unreadable), read without importing numba."""
    try:
        return _cached(module, name, importlib.metadata.version("numba"))
    except Exception:  # whatever goes wrong reading numba's files: as before, compile
        return True


def uncached_seconds() -> float:
    """The measured compile seconds of the kernels numba has no cache entry for (0 when all
    are cached, or when the cache cannot be read)."""
    try:
        numba_version = importlib.metadata.version("numba")
    except importlib.metadata.PackageNotFoundError:
        return 0.0
    total = 0.0
    for (module, name), seconds in KERNELS.items():
        try:
            if not _cached(module, name, numba_version):
                total += seconds
        except Exception:  # whatever goes wrong reading numba's files: say nothing
            continue
    return total


def notice_text(seconds: float) -> str:
    # One kernel left can take under a second: "about 0 s" would read as nothing at all.
    about = f"about {seconds:.0f} s" if seconds >= 1.5 else "a second or so"
    return f"gcs-planner: compiling its kernels once (numba), {about}"


class _Notice:
    """Writes the notice once, at numba's first compile of one of this project's kernels."""

    def __init__(self, stream: TextIO, seconds: float) -> None:
        self.stream = stream
        self.seconds = seconds
        self.done = False

    def on_compile(self, event: Any) -> None:
        dispatcher = (event.data or {}).get("dispatcher")
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
        # The dry run's flight kernels live in sim/, beside the package, and compile as long.
        if self.done or not module.startswith(("gcs_planner.", "sim.")):
            return
        self.done = True
        self.stream.write(notice_text(self.seconds) + "\n")
        self.stream.flush()


def _listen(notice: _Notice) -> None:
    from numba.core import event

    class Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            notice.on_compile(ev)

        def on_end(self, ev: Any) -> None:
            pass

    event.register("numba:compile", Listener())


class _WhenNumbaLoads(importlib.abc.MetaPathFinder):
    """Runs ``then`` once numba is imported: the notice must not import numba itself (a plan
    that needs no kernel never loads it, and the planner picks paths by whether it is loaded).
    ``tag`` names what it is for (one pending hook per tag)."""

    def __init__(self, then: Callable[[], None], tag: str = "notice") -> None:
        self.then = then
        self.tag = tag

    def find_spec(self, name: str, path: Any = None, target: Any = None) -> Any:
        if name != "numba":
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None:
            return spec
        loader = spec.loader
        exec_module = loader.exec_module
        then = self.then

        def exec_then(module: Any) -> None:
            exec_module(module)
            with contextlib.suppress(Exception):  # numba's event API moved: no notice
                then()

        loader.exec_module = exec_then  # type: ignore[method-assign]
        return spec


def maybe_notify(stream: TextIO | None = None, *, quiet: bool = False) -> bool:
    """Arrange the notice on ``stream`` (stderr) when it is a terminal and a kernel is not
    cached: written when numba starts compiling one of the package's kernels, so a plan that
    compiles nothing prints nothing. Whether it was arranged. Off a terminal nothing is
    checked: logs stay as before."""
    stream = stream if stream is not None else sys.stderr
    if quiet or not on_terminal(stream):
        return False
    seconds = uncached_seconds()
    if seconds <= 0:
        return False
    notice = _Notice(stream, seconds)
    # One pending hook at a time (a second plan in the same process replaces the first's).
    when_numba_loads(lambda: _listen(notice), "notice")
    return True


def when_numba_loads(then: Callable[[], None], tag: str) -> None:
    """Run ``then`` now if numba is loaded, else once it is imported (replacing a pending
    ``then`` of the same ``tag``), without importing it."""
    if "numba" in sys.modules:
        with contextlib.suppress(Exception):  # numba's event API moved
            then()
        return
    sys.meta_path[:] = [
        f for f in sys.meta_path if not (isinstance(f, _WhenNumbaLoads) and f.tag == tag)
    ]
    sys.meta_path.insert(0, _WhenNumbaLoads(then, tag))
