"""The result table: one row per cell and front route, as DIR/results.parquet and results.csv.

Both files are rewritten whole and atomically (gcs_planner.runtime.atomic), so whatever moment a
sweep is
stopped at, each file is a complete table of the cells finished by its last write — which is all
``--resume`` needs to know what is done. The columns are fixed, so a table with only failed cells
still reads with the same schema in pandas, polars or DuckDB.
"""

from __future__ import annotations

import io
from pathlib import Path

import pyarrow as pa
import pyarrow.csv as pa_csv
import pyarrow.parquet as pq

from gcs_planner.errors import InputError
from gcs_planner.runtime.atomic import write_atomic
from gcs_planner.sweep.task import PARAMETER_FIELDS

PARQUET = "results.parquet"
CSV = "results.csv"

SCHEMA = pa.schema(
    [
        ("cell", pa.int64()),
        ("cell_key", pa.string()),
        ("status", pa.string()),  # ok, infeasible or error
        ("error", pa.string()),
        # inputs
        ("scenario", pa.string()),
        ("source", pa.string()),
        ("seed", pa.int64()),
        ("unreliable_fraction", pa.float64()),
        ("points", pa.int64()),
        ("unreliable_points", pa.int64()),
        *((name, pa.float64()) for name in PARAMETER_FIELDS),
        ("cruise_airspeed", pa.float64()),
        ("max_bank_angle", pa.float64()),
        ("leg_model", pa.string()),
        ("error_unit", pa.float64()),
        ("capture_radius", pa.float64()),
        ("objectives", pa.string()),
        ("choice", pa.string()),
        ("max_labels", pa.int64()),
        ("time_limit", pa.float64()),
        # the front route
        ("front_size", pa.int64()),
        ("route", pa.int64()),
        ("chosen", pa.bool_()),
        ("length", pa.float64()),
        ("corrections", pa.int64()),
        ("probability", pa.float64()),
        ("proven", pa.bool_()),
        ("gap", pa.float64()),
        ("lower_bound", pa.float64()),
        ("route_ids", pa.string()),
        # the optional dry run of the chosen route
        ("dry_run_runs", pa.int64()),
        ("dry_run_verified", pa.bool_()),
        ("dry_run_arrived", pa.bool_()),
        ("dry_run_success_rate", pa.float64()),
        ("dry_run_ci_low", pa.float64()),
        ("dry_run_ci_high", pa.float64()),
        ("dry_run_confidence", pa.float64()),  # the level of [ci_low, ci_high], e.g. 0.95
        # where and how long
        ("plan_seconds", pa.float64()),
        ("cell_seconds", pa.float64()),
        ("worker", pa.string()),
        ("finished_at", pa.string()),
    ]
)
# The unit of each column that has one: in the Parquet file's schema (each field's "unit"
# metadata, which pyarrow, polars and DuckDB show) and beside the CSV in results.units.csv.
UNITS = {
    # error units (docs/model.md: abstract, decimetres in the paper's Table 2)
    **{k: "error units" for k in ("alpha1", "alpha2", "beta1", "beta2", "theta")},
    "fail_residual": "error units",
    "delta": "error units per m flown",
    "turn_radius": "m",
    "reserve": "m",
    "approach": "m",
    "departure": "m",
    "p_success": "probability",
    "max_climb_angle": "deg",
    "max_descent_angle": "deg",
    "cruise_airspeed": "m/s",
    "max_bank_angle": "deg",
    "error_unit": "m per error unit",
    "capture_radius": "m",
    "time_limit": "s",
    "length": "m",
    "probability": "probability",
    "gap": "fraction of the lower bound",
    "lower_bound": "m",
    "dry_run_success_rate": "fraction of runs",
    "dry_run_ci_low": "fraction of runs",
    "dry_run_ci_high": "fraction of runs",
    "dry_run_confidence": "probability",
    "plan_seconds": "s",
    "cell_seconds": "s",
    "finished_at": "ISO 8601, UTC",
}
SCHEMA = pa.schema(
    [f.with_metadata({"unit": UNITS[f.name]}) if f.name in UNITS else f for f in SCHEMA]
)
COLUMNS = tuple(SCHEMA.names)
UNITS_CSV = "results.units.csv"


class ResultTable:
    """The rows of the finished cells, kept in memory and written to ``out`` on :meth:`save`."""

    def __init__(self, out: Path, rows: list[dict] | None = None) -> None:
        self.out = out
        self.rows: list[dict] = list(rows or [])
        self.done: set[str] = {r["cell_key"] for r in self.rows}

    @classmethod
    def open(cls, out: Path, resume: bool) -> ResultTable:
        """An empty table for a new sweep, or the finished rows of an earlier one (``resume``).

        A new sweep refuses an ``out`` that already holds results rather than overwrite them."""
        path = out / PARQUET
        if out.exists() and not out.is_dir():
            raise InputError("is a file, not a folder for the results", file=str(out))
        try:  # now, not after the first cell: a folder that cannot be made is bad input
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            reason = exc.strerror or str(exc)
            raise InputError(f"cannot create the folder: {reason}", file=str(out)) from None
        if not path.exists():
            return cls(out)
        if not resume:
            raise InputError(
                "already holds results of a sweep: pass --resume to finish it, or another --out",
                file=str(out),
            )
        try:
            table = pq.read_table(path)
        except (OSError, pa.ArrowInvalid) as exc:
            raise InputError(f"cannot read the earlier results: {exc}", file=str(path)) from None
        missing = [c for c in ("cell_key", "status") if c not in table.column_names]
        if missing:
            raise InputError(
                f"not a sweep's results (no column {missing[0]!r})",
                file=str(path),
                field=missing[0],
            )
        return cls(out, table.to_pylist())

    def add(self, rows: list[dict]) -> bool:
        """Add a finished cell's rows; False (and nothing added) when the cell is already in."""
        keys = {r["cell_key"] for r in rows}
        if keys & self.done:
            return False
        self.rows.extend(rows)
        self.done |= keys
        return True

    def drop(self, keys: set[str]) -> int:
        """Remove the rows of the cells ``keys``; returns how many of those cells were in."""
        gone = keys & self.done
        if gone:
            self.rows = [r for r in self.rows if r["cell_key"] not in gone]
            self.done -= gone
        return len(gone)

    def failed(self) -> set[str]:
        """The keys of the cells whose task failed (status "error")."""
        return {r["cell_key"] for r in self.rows if r.get("status") == "error"}

    def to_arrow(self) -> pa.Table:
        rows = sorted(self.rows, key=lambda r: (r.get("cell", 0), r.get("route") or 0))
        return pa.Table.from_pylist([{c: r.get(c) for c in COLUMNS} for r in rows], schema=SCHEMA)

    def save(self) -> tuple[Path, Path]:
        table = self.to_arrow()
        buffer = pa.BufferOutputStream()
        pq.write_table(table, buffer)
        parquet = write_atomic(self.out / PARQUET, buffer.getvalue().to_pybytes())
        text = io.BytesIO()
        pa_csv.write_csv(table, text)
        csv = write_atomic(self.out / CSV, text.getvalue())
        if not (self.out / UNITS_CSV).exists():
            lines = ["column,unit"] + [f"{c},{UNITS.get(c, '')}" for c in COLUMNS]
            write_atomic(self.out / UNITS_CSV, ("\n".join(lines) + "\n").encode())
        return parquet, csv


def read_results(out: str | Path) -> list[dict]:
    """The rows of DIR/results.parquet as dicts (for tests and quick scripts)."""
    return pq.read_table(Path(out) / PARQUET).to_pylist()
