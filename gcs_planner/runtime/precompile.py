"""Compile the planner's numba kernels ahead of need (``gcs-planner compile``).

numba compiles a kernel at its first use and caches it; until then a plan that Python can prove
quickly runs in Python (``core/bnb/context.first_run``), so that a first plan after installing
takes seconds, not the half minute of compiling. Plans that need the kernels compile them
anyway; this command compiles them once, on purpose, so that every later plan is fast: each
kernel is run on a small generated scenario of the same types as any plan's (the kernels are
compiled for one signature each: see core/kernel_records.py), and a small dry run flies the
flight kernels.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Collection

from gcs_planner.runtime.compile_notice import kernel_cached

# (module, function, what it is for), in the order they are compiled.
KERNELS = (
    ("gcs_planner.core.search_kernel", "search", "the branch and bound's searches over walks"),
    ("gcs_planner.core.probe_kernel", "probe", "the probes of the search over simple routes"),
    ("gcs_planner.core.kernel", "fewest_corrections", "straight legs on maps of 3,000+ points"),
    ("gcs_planner.core.kernel", "layered_search", "straight legs on maps of 3,000+ points"),
    ("gcs_planner.core.cost_to_go_kernel", "merge_frontier", "the bounds on maps of 3,000+ points"),
    ("gcs_planner.geometry.airplane_kernel", "airplane_lengths", "the airplane legs' lengths"),
    ("gcs_planner.sim.flight_kernel", "fly_plain", "the dry run's flight (point mass)"),
    ("gcs_planner.sim.flight_kernel", "closest_approach", "the dry run's replay of the track"),
)


def missing() -> list[str]:
    """The kernels numba has not cached (``module.function``)."""
    return [f"{m}.{f}" for m, f, _ in KERNELS if not kernel_cached(m, f)]


# The compile in parts that share no kernel, so that two processes can compile them side by side.
PARTS = ("search", "straight", "bounds", "flight")


def compile_kernels(
    say: Callable[[str], None] = print, parts: Collection[str] = PARTS
) -> list[tuple[str, float]]:
    """Compile (or load from the cache) the kernels of ``KERNELS``: those of ``parts`` (of
    ``PARTS``: the search and its probes, the straight legs' two, the cost-to-go tables of
    large maps, the dry run's flight), all by default; returns (kernel, seconds)."""
    unknown = set(parts) - set(PARTS)
    if unknown:
        raise ValueError(f"no such part of the compile: {sorted(unknown)}; the parts: {PARTS}")
    from gcs_planner.core.bnb import Options, bnb_front
    from gcs_planner.core.cost_to_go import cost_to_go
    from gcs_planner.core.reach import build_reach_graph
    from gcs_planner.core.search import straight_front
    from gcs_planner.scenario.generate import random_scenario
    from gcs_planner.scenario.model import Parameters

    done: list[tuple[str, float]] = []
    # Turns and uncertain corrections, compiled from the first label: the search with the
    # airplane legs, then the probes (this scenario's search over simple routes probes).
    params = Parameters(25, 15, 20, 25, 30, 0.001, turn_radius=200.0, p_success=0.8)
    box = (40_000, 10_000, 500)
    small = random_scenario(14, 2, params=params, box=box, unreliable_fraction=0.3)
    searches = (
        ("search", Options(trial=0, compiled_legs_from=-1, probe_from=10**9)),
        ("probe", Options(trial=0, compiled_legs_from=-1, probe_from=0)),
    )
    for name, options in searches if "search" in parts else ():
        say(f"compiling {name} ...")
        t0 = time.perf_counter()
        bnb_front(small, probability=True, max_labels=20_000, options=options)
        done.append((name, time.perf_counter() - t0))
    # Straight legs on large maps: the fewest corrections of a walk (which focuses the search)
    # and the layered search, compiled here on a small map.
    straight = Parameters(25, 15, 20, 25, 30, 0.001, turn_radius=0.0)
    big = random_scenario(40, 0, params=straight, box=(60_000, 20_000, 500))
    straights = (("fewest_corrections", True), ("layered_search", False))
    for name, focus in straights if "straight" in parts else ():
        say(f"compiling {name} ...")
        t0 = time.perf_counter()
        straight_front(big, compiled=True, focus=focus)
        done.append((name, time.perf_counter() - t0))
    if "bounds" in parts:
        # The cost-to-go tables (the searches' bounds), which maps of 3,000+ points make
        # compiled, with or without turns.
        say("compiling cost_to_go ...")
        t0 = time.perf_counter()
        cost_to_go(big, build_reach_graph(big), compiled=True)
        done.append(("cost_to_go", time.perf_counter() - t0))
    if "flight" in parts:
        say("compiling the dry run's flight ...")
        t0 = time.perf_counter()
        _fly_once()
        done.append(("flight", time.perf_counter() - t0))
    return done


def _fly_once() -> None:
    """One dry run of a small plan, the command's own path (plan, upload to the mock vehicle on
    loopback, the vehicle's flight and the replay): it compiles the flight kernels
    (sim/flight_kernel.py with sim/point_mass_kernel.py and sim/navigator_kernel.py inlined, the
    replay's closest approach) for the types every dry run flies them with."""
    from gcs_planner.core.planner import plan
    from gcs_planner.dryrun.run import dry_run
    from gcs_planner.scenario.generate import random_scenario
    from gcs_planner.scenario.model import Parameters

    params = Parameters(25, 15, 20, 25, 30, 0.001, turn_radius=200.0)
    scenario = random_scenario(12, 0, params=params, box=(20_000, 5_000, 300))
    dry_run(plan(scenario, min_probability=0.0), scenario)
