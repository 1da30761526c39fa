"""MAVProxy (pip `mavproxy`) loads a .waypoints file onto the mock vehicle of both flavours and
saves it back, over UDP on 127.0.0.1, driven through its console as a user types."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.mission.items import MissionItem
from gcs_planner.mission.waypoints import dumps_items, loads_waypoints

ITEMS = [MissionItem(i, 0, 16, x=305_000_000 + 1000 * i, y=1_235_000_000, z=100.0 + i)
         for i in range(6)]  # fmt: skip
DEADLINE_S = 90.0  # generous: an event-driven wait, not a time window


class Console:
    """A MAVProxy process whose output is collected line by line."""

    def __init__(self, port: int, workdir: Path) -> None:
        exe = Path(sys.executable).with_name("mavproxy.py")
        self.proc = subprocess.Popen(
            [sys.executable, str(exe), f"--master=udpout:127.0.0.1:{port}",
             f"--state-basedir={workdir}", "--default-modules=wp"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
            cwd=workdir, env={**os.environ, "MAVLINK20": "1"},
        )  # fmt: skip
        self.lines: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append(line.rstrip())

    def type(self, command: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()

    def wait_for(self, pred) -> bool:
        deadline = time.monotonic() + DEADLINE_S
        while time.monotonic() < deadline:
            if pred():
                return True
            time.sleep(0.1)
        return False

    def close(self) -> str:
        self.proc.terminate()
        try:
            self.proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.communicate()
        return "\n".join(self.lines[-30:])


@pytest.mark.parametrize("flavour", ["ardupilot", "px4"])
def test_mavproxy_loads_and_saves_a_mission(flavour, tmp_path):
    src = tmp_path / "in.waypoints"
    src.write_text(dumps_items(ITEMS, flavour, (30.5, 123.5, 0.0)))
    # MAVProxy sends every row of the file, row 0 included, whatever the autopilot; ArduPilot
    # then keeps its own home in item 0. Read the files the same way: every row an item.
    want = list(loads_waypoints(src.read_text(), "ardupilot").items)
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=flavour) as vehicle:
        console = Console(port, tmp_path)
        try:
            assert console.wait_for(lambda: any("online system" in s for s in console.lines))
            console.type(f"wp load {src}")
            held = lambda: [(it.x, it.z) for it in vehicle.mission]  # noqa: E731
            first = 1 if flavour == "ardupilot" else 0  # ArduPilot keeps its own home
            assert console.wait_for(
                lambda: held()[first:] == [(it.x, it.z) for it in want][first:]
            ), console.close()
            out = tmp_path / "out.waypoints"
            console.type(f"wp save {out}")
            assert console.wait_for(lambda: any(f"to {out}" in s for s in console.lines)), (
                console.close()
            )
        finally:
            console.close()
    back = list(loads_waypoints(out.read_text(), "ardupilot").items)
    assert [(it.x, it.y) for it in back][first:] == [(it.x, it.y) for it in want][first:]
