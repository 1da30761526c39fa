"""What a sweep's worker imports before its first cell, loaded once by the forkserver that the
local cluster's workers are forked from (:mod:`.worker_start`).

``run_cell`` imports the planner lazily, so that the command line starts fast; a worker would
pay for it in its first cell, each worker. Imported here it is paid once, in the forkserver,
and every worker forked from it starts with it.

Not the dry run: it imports numba, and whether numba is imported decides whether a search
flies its legs compiled from the first label (core/bnb/search.py); a forkserver that held numba
would make every worker's results differ in their last bits from a spawned worker's.
"""

from __future__ import annotations

import gcs_planner.core.planner  # noqa: F401
import gcs_planner.sweep.task  # noqa: F401
