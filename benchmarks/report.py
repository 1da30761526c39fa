"""Markdown tables and the description of the machine a run was made on."""

from __future__ import annotations

import datetime
import math
import os
import platform
from collections.abc import Sequence

import numpy as np


def cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def load_average() -> str:
    try:
        return ", ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        return "n/a"


def machine() -> str:
    """One line: CPU, cores, memory, Python, numpy, date, load when the run started."""
    try:
        mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
        memory = f"{mem:.0f} GiB RAM"
    except (ValueError, OSError, AttributeError):
        memory = "RAM n/a"
    return (
        f"{cpu_model()}, {os.cpu_count()} cores, {memory}; Python {platform.python_version()}, "
        f"numpy {np.__version__}; {platform.system()} {platform.release()}; "
        f"{datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}; "
        f"load average at start {load_average()}"
    )


def table(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """A markdown table; numbers right-aligned."""
    cells = [[_cell(c) for c in row] for row in rows]
    right = [
        all(_numeric(row[i]) for row in cells if row[i] not in ("", "–")) and bool(cells)
        for i in range(len(header))
    ]
    lines = [
        "| " + " | ".join(header) + " |",
        "|" + "|".join("---:" if r else "---" for r in right) + "|",
    ]
    lines += ["| " + " | ".join(row) + " |" for row in cells]
    return "\n".join(lines)


def _cell(value: object) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        if math.isnan(value):
            return "–"
        return f"{value:,.3g}" if abs(value) < 1000 else f"{value:,.0f}"
    return str(value)


def _numeric(text: str) -> bool:
    try:
        float(text.replace(",", "").replace("×", "").replace("%", ""))
    except ValueError:
        return False
    return True


def seconds(s: float | None) -> str:
    if s is None:
        return "–"
    return f"{s * 1e3:,.1f} ms" if s < 1 else f"{s:,.2f} s"


def metres(m: float | None) -> str:
    return "–" if m is None or math.isinf(m) else f"{m:,.1f}"


def proof_text(
    proven: bool, largest_gap: float, settled: int, routes: int, complete_below: float | None
) -> str:
    """A front's proof in a table cell: "proven", or its largest gap, how many routes are
    settled and the length below which the front is complete."""
    if proven:
        return "proven"
    below = f", complete below {complete_below:,.0f} m" if complete_below else ""
    return f"gap {largest_gap:,.0f} m, {settled}/{routes} routes settled{below}"
