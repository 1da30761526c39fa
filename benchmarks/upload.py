"""Section 5: a 1,000-item mission uploaded and verified over loopback UDP, no faults."""

from __future__ import annotations

import statistics

from benchmarks.report import seconds, table
from sim.vehicle import benchmark_upload

FLAVOURS = ("ardupilot", "px4")


def run_upload(items: int, runs: int) -> list[list[str]]:
    rows = []
    for flavour in FLAVOURS:
        done = [benchmark_upload(items, flavour) for _ in range(runs)]
        rows.append(
            [
                flavour,
                f"{items:,}",
                seconds(statistics.median(d["upload_seconds"] for d in done)),
                seconds(statistics.median(d["verify_seconds"] for d in done)),
                seconds(statistics.median(d["seconds"] for d in done)),
                f"{max(d['retries'] for d in done):g}",
            ]
        )
    return rows


def render(rows: list[list[str]]) -> str:
    head = ["mock vehicle", "items", "upload", "read back", "total (median)", "retries (most)"]
    return table(head, rows)
