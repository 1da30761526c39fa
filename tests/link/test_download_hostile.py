"""`gcs-planner download` from a hostile vehicle: a responder on UDP 127.0.0.1 that speaks the
mission protocol correctly but serves arbitrary item values. Whatever it serves, the command
writes a valid file equal to what was served (exit 0), or writes nothing and exits 4 naming
the first invalid item's seq and field; never an invalid file, never a traceback."""

from __future__ import annotations

import json
import math
import socket
import threading
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from gcs_planner.cli import main
from gcs_planner.link.connection import mavlink
from gcs_planner.link.protocol import Tolerance, item_differences
from gcs_planner.mission.items import MissionItem
from gcs_planner.mission.waypoints import loads_waypoints

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

INT32_MAX = 2**31 - 1
PX4 = mavlink.MAV_AUTOPILOT_PX4
ARDUPILOT = mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA


class HostileVehicle:
    """Answers HEARTBEAT, MISSION_REQUEST_LIST and MISSION_REQUEST(_INT) as a vehicle does,
    with ``items`` as they are (``legacy`` items as float MISSION_ITEM, the rest _INT)."""

    def __init__(
        self, items: list[MissionItem], legacy: frozenset[int] = frozenset(), autopilot: int = PX4
    ) -> None:
        self.items = items
        self.autopilot = autopilot
        self.legacy = legacy
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.05)
        self.port = self.sock.getsockname()[1]
        self.mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.parser = mavlink.MAVLink(None)
        self.parser.robust_parsing = True
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _send(self, msg: object, addr: object) -> None:
        self.sock.sendto(bytes(msg.pack(self.mav)), addr)  # type: ignore[attr-defined]

    def _run(self) -> None:
        while not self.stop.is_set():
            try:
                data, addr = self.sock.recvfrom(65535)
            except (TimeoutError, OSError):
                continue
            for msg in self.parser.parse_buffer(data) or []:
                self._answer(msg, addr)

    def _answer(self, msg: object, addr: object) -> None:
        kind = msg.get_type()  # type: ignore[attr-defined]
        if kind == "HEARTBEAT":
            self._send(self.mav.heartbeat_encode(1, self.autopilot, 0, 0, 3), addr)
        elif kind == "MISSION_REQUEST_LIST":
            self._send(self.mav.mission_count_encode(255, 190, len(self.items), 0), addr)
        elif kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            seq = msg.seq  # type: ignore[attr-defined]
            if seq >= len(self.items):
                return
            it = self.items[seq]
            if seq in self.legacy:
                fields = (it.x / 1e7, it.y / 1e7)
                encode = self.mav.mission_item_encode
            else:
                fields = (it.x, it.y)
                encode = self.mav.mission_item_int_encode
            self._send(
                encode(255, 190, seq, it.frame, it.command, it.current, it.autocontinue,
                       it.param1, it.param2, it.param3, it.param4, *fields, it.z, 0),
                addr,
            )  # fmt: skip

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=5.0)
        self.sock.close()


# The test's own idea of an item a mission file may hold, written apart from the code's.
def acceptable(it: MissionItem) -> bool:
    commands = {v for v, e in mavlink.enums["MAV_CMD"].items() if not e.name.endswith("END")}
    if it.frame not in (0, 2, 3, 5, 6) or it.command not in commands:
        return False
    params = (it.param1, it.param2, it.param3, it.param4)
    if any(math.isinf(p) for p in params) or not math.isfinite(it.z):
        return False
    if it.command in (16, 17, 18, 19, 21, 22, 31) and it.frame != 2:
        return abs(it.x) <= 900_000_000 and abs(it.y) <= 1_800_000_000 and -1000 <= it.z <= 1e5
    return True


def f32(value: float) -> float:
    import struct

    return struct.unpack("<f", struct.pack("<f", value))[0]


FLOATS = st.one_of(
    st.floats(width=32, allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, 25.0, -1.0, math.nan, math.inf, 1e30, 5000.0, 100_000.5]),
).map(lambda v: f32(v))  # what goes on the wire, as float32
COORD = st.one_of(
    st.integers(-(2**31), INT32_MAX),
    st.sampled_from([305_000_000, 900_000_000, 900_000_001, -1_800_000_000, INT32_MAX, 0]),
)
ITEMS = st.lists(
    st.builds(
        MissionItem,
        seq=st.just(0),
        frame=st.sampled_from([0, 0, 3, 6, 2, 1, 10, 99]),
        command=st.sampled_from([16, 16, 16, 178, 20, 21, 65535, 12345]),
        current=st.sampled_from([0, 0, 1]),
        autocontinue=st.just(1),
        param1=FLOATS,
        param2=FLOATS,
        param3=FLOATS,
        param4=FLOATS,
        x=COORD,
        y=COORD,
        z=FLOATS,
    ),
    min_size=0,
    max_size=4,
)


HOME = MissionItem(0, 0, 16, x=305_000_000, y=1_235_000_000, z=5.0)
LEG = MissionItem(1, 3, 16, x=305_100_000, y=1_235_000_000, z=100.0)
DO_JUMP = MissionItem(2, 2, 177, param1=1.0, param2=3.0)


def _same(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))


@settings(
    max_examples=30,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(
    served=ITEMS,
    suffix=st.sampled_from([".json", ".waypoints"]),
    autopilot=st.sampled_from([PX4, ARDUPILOT]),
)
# The writes a random draw rarely reaches: a valid ArduPilot mission to .waypoints and to JSON.
@example(served=[HOME, LEG, DO_JUMP], suffix=".waypoints", autopilot=ARDUPILOT)
@example(served=[HOME, LEG, DO_JUMP], suffix=".json", autopilot=PX4)
def test_download_writes_what_was_served_or_nothing(
    tmp_path_factory, capsys, served, suffix, autopilot
):
    served = [it.with_seq(k) for k, it in enumerate(served)]
    out: Path = tmp_path_factory.mktemp("dl") / f"mission{suffix}"
    vehicle = HostileVehicle(served, autopilot=autopilot)
    try:
        conn = f"udpout:127.0.0.1:{vehicle.port}"
        code = main(["download", "--connect", conn, "--quiet", "--timeout", "0.5", "--out",
                     str(out)])  # fmt: skip
    finally:
        vehicle.close()
    captured = capsys.readouterr()
    bad = [it.seq for it in served if not acceptable(it)]
    as_waypoints = suffix == ".waypoints"
    # ArduPilot's item 0 is home: in a .waypoints file it is row 0, which must be a place
    # (asked once every item is valid).
    home_bad = served and not is_place(served[0])
    if not bad and as_waypoints and autopilot == ARDUPILOT and home_bad:
        bad = [0]
    if bad:
        assert code == 4, captured
        assert not out.exists()
        err = captured.err.strip()
        assert "\n" not in err and "Traceback" not in err
        assert f"seq {bad[0]}," in err, err
        return
    if as_waypoints and autopilot == PX4:
        # A PX4 mission is not written as .waypoints (readers disagree on its row 0): refused
        # once the items are in, and nothing written.
        assert code == 2 and not out.exists(), captured
        assert "use --out FILE.json" in captured.err and "\n" not in captured.err.strip()
        return
    assert code == 0, captured.err
    if not as_waypoints:
        got = json.loads(out.read_text())["items"]
        assert len(got) == len(served)
        for row, it in zip(got, served, strict=True):
            for name, value in row.items():
                want = getattr(it, name)
                assert _same(float(value), float(want)), (name, value, want)
        return
    read = loads_waypoints(out.read_text(), "ardupilot")
    assert len(read.items) == max(1, len(served))  # row 0 is home even with no items
    if served:
        home = served[0]
        assert read.home[0] * 1e7 == pytest.approx(home.x, abs=1) and read.home[2] == pytest.approx(
            home.z, abs=1e-6
        )
    for g, it in zip(read.items[1:], served[1:], strict=True):
        assert acceptable(g)
        # .waypoints keeps 6 decimals of params and altitude: equal within them.
        assert not item_differences(it, g, Tolerance(param_abs=1e-6, param_rel=1e-6)), (g, it)


def is_place(it: MissionItem) -> bool:
    return it.command in (16, 17, 18, 19, 21, 22, 31) and it.frame in (0, 3, 5, 6)


@pytest.mark.parametrize("lat", [math.nan, math.inf, 1e30, 300.0])
def test_a_legacy_item_without_a_real_latitude_is_refused(tmp_path, capsys, lat):
    """The issue's case: a NaN latitude was written as 214.7483647 (INT32_MAX degE7)."""
    home = MissionItem(0, 0, 16, x=305_000_000, y=1_235_000_000, z=10.0)
    wp = MissionItem(1, 3, 16, x=0, y=1_235_000_000, z=100.0)
    vehicle = HostileVehicle([home, wp], legacy=frozenset({1}))
    # The responder sends x / 1e7 as the float latitude: give it the degrees times 1e7.
    vehicle.items[1] = MissionItem(1, 3, 16, x=lat * 1e7, y=1_235_000_000, z=100.0)  # type: ignore[arg-type]
    out = tmp_path / "m.waypoints"
    try:
        conn = f"udpout:127.0.0.1:{vehicle.port}"
        code = main(["download", "--connect", conn, "--quiet", "--out", str(out)])
    finally:
        vehicle.close()
    err = capsys.readouterr().err.strip()
    assert code == 4 and not out.exists()
    assert "seq 1, field 'lat'" in err and "\n" not in err, err
