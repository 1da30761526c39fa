"""Each workbook read once for a test module: ``xlsx.read_workbook_cells`` remembered by the
file (its resolved path, size and modification time), a copy of the same cells handed to each
reader. openpyxl's read of a contest workbook is a good part of each `plan` or `dry-run` that
a test runs in process; what is made of the cells (the scenario, its checks) is done afresh."""

from __future__ import annotations

import copy
from collections.abc import Iterator
from pathlib import Path

import pytest


def read_workbooks_once() -> Iterator[None]:
    """For a module-scoped fixture: ``read_workbook_cells`` remembered until it ends."""
    from gcs_planner.scenario import xlsx

    read = xlsx.read_workbook_cells
    cells: dict[tuple, object] = {}

    def read_once(path: Path):  # noqa: ANN202 - xlsx.read_workbook_cells's CellTable
        where = Path(path).resolve()
        stat = where.stat()
        key = (where, stat.st_size, stat.st_mtime_ns)
        if key not in cells:
            cells[key] = read(path)
        return copy.deepcopy(cells[key])

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(xlsx, "read_workbook_cells", read_once)
        yield
