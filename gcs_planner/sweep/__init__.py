"""Sweeps: studies over many scenarios and parameter values, each cell one task on Dask.

    from gcs_planner.sweep import run_sweep
    result = run_sweep("missions/sweep-example.toml", "out/sweep")   # a local cluster
    result = run_sweep(spec, "out/sweep", scheduler="tcp://10.0.0.5:8786", resume=True)

Needs the ``sweep`` extra (``pip install 'gcs-planner[sweep]'``: dask.distributed and pyarrow);
reading a spec and running one cell (:func:`run_cell`) do not.
"""

from __future__ import annotations

from gcs_planner.sweep.cells import Cell, expand
from gcs_planner.sweep.runner import SweepResult, run_sweep
from gcs_planner.sweep.spec import SweepSpec, read_spec
from gcs_planner.sweep.task import run_cell

__all__ = [
    "Cell",
    "SweepResult",
    "SweepSpec",
    "expand",
    "missing_dependencies",
    "read_results",
    "read_spec",
    "run_cell",
    "run_sweep",
]

INSTALL_HINT = "pip install 'gcs-planner[sweep]' (from a checkout: pip install '.[sweep]')"


def missing_dependencies() -> list[str]:
    """The sweep's optional packages that are not installed (empty when it can run)."""
    import importlib.util

    return [name for name in ("distributed", "pyarrow") if importlib.util.find_spec(name) is None]


def read_results(out: str) -> list[dict]:
    """The rows of ``out``/results.parquet as dicts."""
    from gcs_planner.sweep.table import read_results as read

    return read(out)
