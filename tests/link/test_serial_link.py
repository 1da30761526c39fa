"""A serial link end to end: the mock vehicle and `gcs-planner upload` / `download` on the two
ends of a pseudo-terminal cable (two pty pairs joined by a byte pump, as socat would join them),
through pyserial as with a telemetry radio on /dev/ttyUSB0."""

from __future__ import annotations

import json
import os
import pty
import select
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from gcs_planner.sim.vehicle import MockVehicle

from gcs_planner.cli import main
from gcs_planner.mission.items import MissionItem
from gcs_planner.mission.waypoints import dumps_items


@contextmanager
def serial_cable() -> Iterator[tuple[str, str]]:
    """Two serial device paths whose bytes reach each other."""
    m1, s1 = pty.openpty()
    m2, s2 = pty.openpty()
    stop = threading.Event()

    def pump() -> None:
        peer = {m1: m2, m2: m1}
        while not stop.is_set():
            ready, _, _ = select.select([m1, m2], [], [], 0.05)
            for fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:
                    continue
                if data:
                    os.write(peer[fd], data)

    thread = threading.Thread(target=pump, daemon=True)
    thread.start()
    try:
        yield os.ttyname(s1), os.ttyname(s2)
    finally:
        stop.set()
        thread.join(timeout=5.0)
        for fd in (m1, s1, m2, s2):
            os.close(fd)


def test_upload_and_download_over_a_serial_cable(tmp_path: Path, capsys) -> None:
    items = [
        MissionItem(i, 0, 16, param2=30.0, x=305_000_000 + 500 * i, y=1_235_000_000, z=120.0)
        for i in range(12)
    ]
    wp = tmp_path / "m.waypoints"
    wp.write_text(dumps_items(items, "px4", (30.5, 123.5, 0.0)))
    with serial_cable() as (vehicle_end, gcs_end):
        with MockVehicle(vehicle_end, flavour="px4", baud=57600) as vehicle:
            conn = ["--connect", gcs_end, "--baud", "57600", "--quiet"]
            assert main(["upload", str(wp), *conn]) == 0, capsys.readouterr().err
            assert [(it.x, it.z) for it in vehicle.mission] == [(it.x, it.z) for it in items]
            out = tmp_path / "back.json"
            assert main(["download", *conn, "--out", str(out)]) == 0
            back = json.loads(out.read_text())["items"]
            assert [row["x"] for row in back] == [it.x for it in items]
    assert "uploaded and verified 12 items" in capsys.readouterr().out
