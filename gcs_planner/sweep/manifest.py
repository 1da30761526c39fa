"""What a results folder was made from: a copy of the spec and the planner's version beside the
table, so that ``--resume`` trusts the spec rather than the old table.

DIR/spec.toml is the spec as it was when the sweep last started, DIR/sweep.json the planner's
version and the key of every cell of it. A resumed sweep compares the keys (a digest of each
cell's full description, :attr:`Cell.key`) with the spec given now: any cell added or gone is a
changed spec, refused unless ``--prune`` (which drops the rows of the cells no longer in it); a
changed comment or order is not. The kept rows are renumbered to the spec given now, so that a
cell number names one cell only.
"""

from __future__ import annotations

import difflib
import json
from pathlib import Path

from gcs_planner import __version__
from gcs_planner.errors import InputError
from gcs_planner.runtime.atomic import write_atomic
from gcs_planner.sweep.cells import Cell
from gcs_planner.sweep.spec import SweepSpec

MANIFEST = "sweep.json"
SPEC_COPY = "spec.toml"


def _spec_text(spec: SweepSpec) -> str:
    try:
        return Path(spec.path).read_text(encoding="utf-8")
    except OSError:
        return ""


def write_manifest(out: Path, spec: SweepSpec, cells: list[Cell]) -> None:
    """DIR/spec.toml and DIR/sweep.json for the sweep about to run."""
    write_atomic(out / SPEC_COPY, _spec_text(spec))
    manifest = {
        "planner_version": __version__,
        "spec": spec.path,
        "name": spec.name,
        "cells": [c.key for c in cells],
    }
    write_atomic(out / MANIFEST, json.dumps(manifest, indent=1) + "\n")


def check_resume(out: Path, spec: SweepSpec, cells: list[Cell], table, prune: bool) -> list[str]:
    """Check the folder's results against ``spec`` before a resume; drop the rows of cells no
    longer in it when ``prune``; renumber the kept rows. Returns what to tell the user."""
    notes: list[str] = []
    current = {c.key: c for c in cells}
    saved: dict = {}
    path = out / MANIFEST
    if path.exists():
        try:
            saved = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise InputError(f"cannot read the sweep's record: {exc}", file=str(path)) from None
    saved_keys = set(saved.get("cells", ())) | table.done
    gone = saved_keys - current.keys()
    new = current.keys() - saved_keys if saved else set()
    if gone or new:
        what = f"{len(gone)} cells no longer in it, {len(new)} new"
        change = _first_change(out / SPEC_COPY, spec)
        if not prune:
            raise InputError(
                f"the spec changed since these results were saved ({what}"
                + (f"; {change}" if change else "")
                + "): pass --resume --prune to drop the rows of the cells no longer in it, "
                "or another --out",
                file=spec.path,
            )
        dropped = table.drop(gone)
        notes.append(f"spec changed ({what}): dropped the rows of {dropped} cells")
    version = saved.get("planner_version")
    if version and version != __version__:
        notes.append(
            f"note: the kept cells were planned by gcs-planner {version}, this is {__version__}"
        )
    for row in table.rows:  # numbers of the spec given now: one number, one cell
        row["cell"] = current[row["cell_key"]].index
    return notes


def _first_change(saved_copy: Path, spec: SweepSpec) -> str:
    """The first line that differs between the saved copy of the spec and the spec now."""
    try:
        before = saved_copy.read_text(encoding="utf-8").splitlines()
    except OSError:
        return ""
    after = _spec_text(spec).splitlines()
    matcher = difflib.SequenceMatcher(a=before, b=after, autojunk=False)
    for tag, i1, i2, j1, j2 in matcher.get_opcodes():
        if tag == "equal":
            continue
        old = before[i1].strip() if i1 < i2 else ""
        now = after[j1].strip() if j1 < j2 else ""
        if old and now:
            return f"line {j1 + 1} was {old!r}, is now {now!r}"
        if now:
            return f"line {j1 + 1} {now!r} is new"
        return f"line {i1 + 1} {old!r} was removed"
    return ""
