"""Section 5: a 1,000-item mission uploaded and verified over loopback UDP, no faults."""

from __future__ import annotations

import statistics

from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from benchmarks.report import seconds, table
from gcs_planner.aircraft.profile import FIRMWARES
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.mission.items import MissionItem

FLAVOURS = FIRMWARES


def benchmark_upload(n_items: int = 1000, flavour: str = "ardupilot") -> dict[str, float]:
    """Upload and verify an ``n_items`` mission to a mock vehicle over UDP loopback, no faults.

    Returns the seconds taken (total, upload, read-back) for the benchmark to report.
    """
    port = free_udp_port()
    items = [
        MissionItem(i, 0, 16, x=305_000_000 + 97 * i, y=1_235_000_000 + 89 * i, z=500.0 + i % 7)
        for i in range(n_items)
    ]
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour, capacity=max(n_items, 1)):
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, transfer="mission")  # this table is the protocol's
            client.connect(timeout=10.0)
            report = client.upload_verified(items)
        finally:
            link.close()
    return {
        "items": float(n_items),
        "seconds": report.seconds,
        "upload_seconds": report.upload_seconds,
        "verify_seconds": report.verify_seconds,
        "retries": float(report.retries),
    }


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
