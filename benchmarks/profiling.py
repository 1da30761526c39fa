"""Section 5: where ``straight_front`` spends its time (cProfile, top functions)."""

from __future__ import annotations

import cProfile
import io
import pstats

from benchmarks.cases import load_case
from gcs_planner.core.search import straight_front

PROFILE_CASES = ("dataset1", "random-5000")


def profile(specs: tuple[str, ...] = PROFILE_CASES, top: int = 15) -> str:
    """The top ``top`` functions by cumulative time of one ``straight_front`` per scenario."""
    out = []
    for spec in specs:
        scenario = load_case(spec)
        profiler = cProfile.Profile()
        profiler.enable()
        straight_front(scenario)
        profiler.disable()
        buf = io.StringIO()
        pstats.Stats(profiler, stream=buf).sort_stats("cumulative").print_stats(top)
        out.append(
            f"### straight_front on {spec} ({scenario.n} points)\n\n```\n"
            f"{buf.getvalue().strip()}\n```"
        )
    return "\n\n".join(out)
