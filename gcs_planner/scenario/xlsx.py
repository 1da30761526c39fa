"""Layout of the contest workbook: which sheet, which row is the header, which column is what.

The two contest files differ in their headers (column E ``校正点类型`` or ``校正点标记``; units
written ``（单位: m）`` or ``（单位:m）``; trailing empty columns), so the header is recognised by
its content once spaces and full-width punctuation are normalised, not by exact text. Meaning of
the cells is checked in readers. Row numbers are the spreadsheet's own 1-based numbers.
"""

from __future__ import annotations

import re
import unicodedata
import warnings
from pathlib import Path

import openpyxl
from openpyxl.utils import get_column_letter
from openpyxl.workbook.workbook import Workbook

from gcs_planner.errors import InputError

# (header row, [(row, {column: cell value})], {column: label used in error messages})
CellTable = tuple[int, list[tuple[int, dict[str, object]]], dict[str, str]]

# Accepted header texts per column, after _normalise. Both "标记" headers exist: in dataset 2
# "校正点标记" is the *type* column, so the flag column is only recognised by its fuller names.
HEADER_NAMES: dict[str, frozenset[str]] = {
    "id": frozenset({"编号", "id", "序号"}),
    "x": frozenset({"x坐标", "x"}),
    "y": frozenset({"y坐标", "y"}),
    "z": frozenset({"z坐标", "z"}),
    "kind": frozenset({"校正点类型", "校正点标记", "类型", "kind", "type"}),
    "unreliable": frozenset({"第三问点标记", "第三问标记", "unreliable", "flag"}),
}
# What an error message calls each column, so that a user finds it in the contest's wording.
HEADER_HINTS = {
    "id": "编号",
    "x": "X坐标（单位: m）",
    "y": "Y坐标（单位: m）",
    "z": "Z坐标（单位: m）",
    "kind": "校正点类型",
    "unreliable": "第三问点标记",
}
EXPECTED_HEADER_ROW = 2  # row 1 of the contest files is a note
_SEARCH_ROWS = 5  # how far down a header row is looked for
_UNIT = re.compile(r"\(.*\)$")


def _normalise(cell: object) -> str:
    """Header text without spaces, full-width forms, case or a trailing unit in parentheses."""
    if cell is None:
        return ""
    text = unicodedata.normalize("NFKC", str(cell))
    text = re.sub(r"\s+", "", text).lower()
    return _UNIT.sub("", text)


def _columns(header: tuple[object, ...]) -> dict[str, int]:
    """Column index of each recognised column of a header row."""
    found: dict[str, int] = {}
    for position, cell in enumerate(header):
        name = _normalise(cell)
        for column, accepted in HEADER_NAMES.items():
            if name in accepted and column not in found:
                found[column] = position
    return found


def _open(path: Path) -> Workbook:
    try:
        return openpyxl.load_workbook(path, read_only=True, data_only=True)
    except Exception as exc:  # openpyxl raises many types for a damaged or foreign file
        raise InputError(
            f"not a readable .xlsx workbook ({type(exc).__name__}: {exc})", file=str(path)
        ) from None


def read_workbook_cells(path: Path) -> CellTable:
    """Header row and each non-empty point row of the first sheet that has the header."""
    with warnings.catch_warnings():
        # The contest files carry an Excel extension openpyxl does not know; it is harmless.
        warnings.filterwarnings(
            "ignore", message=".*extension is not supported", category=UserWarning
        )
        workbook = _open(path)
        try:
            return _read(path, workbook)
        except InputError:
            raise
        except Exception as exc:  # a damaged sheet part surfaces only while rows are read
            raise InputError(
                f"not a readable .xlsx workbook ({type(exc).__name__}: {exc})", file=str(path)
            ) from None
        finally:
            workbook.close()


def _read(path: Path, workbook: Workbook) -> CellTable:
    # The header is the row, among the first few of any sheet, that names the most columns.
    best: tuple[int, dict[str, int], list[tuple[object, ...]]] | None = None
    any_cells = False
    for sheet in workbook.worksheets:
        sheet.reset_dimensions()  # some writers store a wrong sheet size
        rows = [tuple(r) for r in sheet.iter_rows(values_only=True)]
        any_cells = any_cells or any(not _blank(c) for r in rows for c in r)
        for number, row in enumerate(rows[:_SEARCH_ROWS], start=1):
            columns = _columns(row)
            if len(columns) >= 2 and (best is None or len(columns) > len(best[1])):
                best = (number, columns, rows)
        if best is not None and len(best[1]) == len(HEADER_NAMES):
            break
    if best is None:
        if not any_cells:
            raise InputError("empty workbook: no cells", file=str(path))
        names = ", ".join(HEADER_HINTS.values())
        raise InputError(
            f"no header row found in any sheet (expected columns {names}, "
            "as in the contest workbook)",
            file=str(path),
            row=EXPECTED_HEADER_ROW,
            field="id",
        )
    header_row, columns, rows = best
    missing = [c for c in HEADER_NAMES if c not in columns]
    if missing:
        raise InputError(
            "missing column(s) " + ", ".join(f"{c} ({HEADER_HINTS[c]})" for c in missing),
            file=str(path),
            row=header_row,
            field=missing[0],
        )
    labels = {c: f"{c} (column {get_column_letter(p + 1)})" for c, p in columns.items()}
    cells: list[tuple[int, dict[str, object]]] = []
    for number, row in enumerate(rows[header_row:], start=header_row + 1):
        values = {c: (row[p] if p < len(row) else None) for c, p in columns.items()}
        if all(_blank(v) for v in values.values()):
            continue  # spreadsheets often end with formatted but empty rows
        cells.append((number, values))
    return header_row, cells, labels


def _blank(value: object) -> bool:
    return value is None or (isinstance(value, str) and not value.strip())
