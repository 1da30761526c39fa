"""What a sweep's worker imports before its first cell, loaded once by the forkserver that the
local cluster's workers are forked from (:mod:`.worker_start`).

``run_cell`` imports the planner lazily, so that the command line starts fast; a worker would
pay for it in its first cell, each worker. Imported here it is paid once, in the forkserver,
and every worker forked from it starts with it.

A cell loads numba before it plans (``task._compiled_legs``): it is imported here too, and the
compiled airplane legs loaded from numba's cache by flying one leg, so that a worker starts with
them (about a second of CPU each otherwise). A spawned worker (one that Dask's nanny restarted)
runs this module itself and plans the same way.
"""

from __future__ import annotations

import numpy as np

import gcs_planner.core.planner  # noqa: F401
import gcs_planner.sweep.task  # noqa: F401
from gcs_planner.geometry.legs import AirplaneLegs


def _fly_one_leg() -> None:
    # The dispatcher compiles (or loads from the cache) on its first call with these types.
    start = np.zeros(3)
    heading = np.array([1.0, 0.0, 0.0])
    end = np.array([[1000.0, 500.0, 10.0]])
    AirplaneLegs(200.0, 15.0, 15.0).compiled_lengths(start, heading, end)


_fly_one_leg()
