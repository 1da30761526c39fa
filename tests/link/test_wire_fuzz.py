"""Hostile MAVLink on the wire, thrown by hypothesis over UDP on 127.0.0.1.

The vehicle: every message type it handles, with NaN, infinities and extreme values in every
field, and truncated, corrupted and random frames. After each batch it must still answer, must
have raised in no handler, must hold only items it can send back, and must still hold its
mission unless the batch carried a clear or an upload.

The ground station: a fake vehicle answers a download with hostile frames; the client returns
items or a LinkError, never anything else.
"""

from __future__ import annotations

import socket
import struct
import threading
import time
from typing import Any

import pytest
from gcs_planner.sim.mission_server import check_item
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcs_planner.errors import LinkError
from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import item_to_message
from gcs_planner.mission.items import MissionItem

# Mostly waiting on protocol timers: started first in each test process (tests/conftest.py).
pytestmark = pytest.mark.waits

VEHICLE_TYPES = (
    "HEARTBEAT", "MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_REQUEST_LIST",
    "MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK", "MISSION_CLEAR_ALL",
    "MISSION_SET_CURRENT", "COMMAND_LONG", "PARAM_SET", "PARAM_REQUEST_READ",
    "PARAM_REQUEST_LIST",
)  # fmt: skip
CLIENT_TYPES = (
    "HEARTBEAT", "MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_REQUEST",
    "MISSION_REQUEST_INT", "MISSION_ACK", "MISSION_CURRENT", "COMMAND_ACK", "STATUSTEXT",
    "PARAM_VALUE",
)  # fmt: skip
MUTATING = {"MISSION_CLEAR_ALL", "MISSION_COUNT"}
REFERENCE = [
    MissionItem(i, 0, 16, x=305_000_000 + 100 * i, y=1_235_000_000, z=100.0) for i in range(4)
]
HOSTILE_FLOATS = st.one_of(
    st.floats(width=32, allow_nan=True, allow_infinity=True),
    st.sampled_from([float("nan"), float("inf"), -float("inf"), 3.4e38, -3.4e38, 3e5, 1e-45]),
)
_INT_RANGES = {
    "uint8_t": (0, 2**8 - 1), "int8_t": (-(2**7), 2**7 - 1),
    "uint16_t": (0, 2**16 - 1), "int16_t": (-(2**15), 2**15 - 1),
    "uint32_t": (0, 2**32 - 1), "int32_t": (-(2**31), 2**31 - 1),
    "uint64_t": (0, 2**64 - 1), "int64_t": (-(2**63), 2**63 - 1),
}  # fmt: skip
# Values that reach the handlers more often than uniform integers would.
_LIKELY = {
    "target_system": st.sampled_from([1, 1, 1, 0, 2]),
    "target_component": st.sampled_from([1, 1, 0, 190]),
    "mission_type": st.sampled_from([0, 0, 1, 2, 255, 9]),
    "command": st.sampled_from([16, 177, 201, 300, 224, 9999, 0]),
    "frame": st.sampled_from([0, 2, 3, 5, 6, 11, 99]),
    "seq": st.integers(0, 6),
    "count": st.sampled_from([0, 1, 3, 65535]),
    "param_index": st.integers(-2, 10),
}


def _field(name: str, kind: str, length: int) -> st.SearchStrategy[Any]:
    if kind == "char":
        return st.binary(max_size=max(length, 1))
    if kind in ("float", "double"):
        return HOSTILE_FLOATS
    lo, hi = _INT_RANGES[kind]
    ints = st.integers(lo, hi)
    if name not in _LIKELY:
        return ints
    return st.one_of(_LIKELY[name].map(lambda v: min(max(v, lo), hi)), ints)


def message(kind: str) -> st.SearchStrategy[Any]:
    cls = getattr(mavlink, f"MAVLink_{kind.lower()}_message")
    lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths))
    fields = [_field(n, t, lengths.get(n, 0)) for n, t in zip(cls.fieldnames, cls.fieldtypes)]
    return st.tuples(*fields).map(lambda values: cls(*values))


def frames(types: tuple[str, ...], mav: Any) -> st.SearchStrategy[tuple[str, bytes]]:
    """(type, bytes): a well-formed frame, or one truncated, corrupted or random."""
    packed = (
        st.sampled_from(types).flatmap(message).map(lambda m: (m.get_type(), bytes(m.pack(mav))))
    )

    def truncate(pair: tuple[str, bytes], cut: int) -> tuple[str, bytes]:
        return "broken", pair[1][: max(1, cut % len(pair[1]))]

    def corrupt(pair: tuple[str, bytes], at: int, xor: int) -> tuple[str, bytes]:
        buf = bytearray(pair[1])
        buf[at % len(buf)] ^= xor
        return "broken", bytes(buf)

    return st.one_of(
        packed,
        packed,
        st.builds(truncate, packed, st.integers(0, 300)),
        st.builds(corrupt, packed, st.integers(0, 300), st.integers(1, 255)),
        st.binary(min_size=1, max_size=300).map(lambda b: ("broken", b)),
        st.binary(min_size=1, max_size=40).map(lambda b: ("broken", b"\xfd" + b)),
    )


def _wait(link: Any, pred: Any, timeout: float = 10.0) -> Any | None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = link.recv(0.05)
        if msg is not None and pred(msg):
            return msg
    return None


@pytest.fixture(scope="module", params=["ardupilot", "px4"])
def vehicle_and_link(request):
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour=request.param) as vehicle:
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link, timeout=1.0)
            client.connect(timeout=10.0)
            yield vehicle, link, client
        finally:
            link.close()


_PACKER = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)


@settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(batch=st.lists(frames(VEHICLE_TYPES, _PACKER), min_size=1, max_size=12))
def test_the_vehicle_survives_anything_on_the_wire(vehicle_and_link, batch):
    vehicle, link, client = vehicle_and_link
    client.upload(REFERENCE)
    for _, frame in batch:
        link.write_raw(frame)
    # Cancel any upload the batch started, then a round trip that proves the loop is alive
    # and has handled everything before it (one socket, in order).
    link.send(link.mav.mission_ack_encode(1, 1, mavlink.MAV_MISSION_OPERATION_CANCELLED, 0))
    link.send(link.mav.param_request_read_encode(1, 1, b"", 0))
    assert _wait(link, lambda m: m.get_type() == "PARAM_VALUE") is not None
    assert vehicle.handler_errors == 0
    held = vehicle.mission
    for item in held:
        assert check_item(item) == mavlink.MAV_MISSION_ACCEPTED
        item_to_message(link.mav, item, 255, 190).pack(link.mav)  # it can be sent back
    if not MUTATING & {kind for kind, _ in batch}:
        expected = REFERENCE if vehicle.flavour == "px4" else held[:1] + REFERENCE[1:]
        assert held == expected
    back = client.download()
    assert [it.x for it in back] == [it.x for it in held]


# The ground station's side ----------------------------------------------------------------------
_VEHICLE_PACKER = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)


class FakeVehicle:
    """Listens on a UDP port; answers the first datagram it hears with a scripted burst."""

    def __init__(self, script: list[bytes]) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.05)
        self.port = self.sock.getsockname()[1]
        self.script = script
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stop.is_set():
            try:
                _, addr = self.sock.recvfrom(65535)
            except (TimeoutError, OSError):
                continue
            for frame in self.script:
                self.sock.sendto(frame, addr)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(timeout=5.0)
        self.sock.close()


def _count(n: int) -> bytes:
    return bytes(_VEHICLE_PACKER.mission_count_encode(255, 190, n, 0).pack(_VEHICLE_PACKER))


@settings(max_examples=25, deadline=None)
@given(
    count=st.integers(0, 3),
    burst=st.lists(frames(CLIENT_TYPES, _VEHICLE_PACKER), min_size=1, max_size=15),
)
def test_the_ground_station_parser_survives_a_hostile_vehicle(count, burst):
    fake = FakeVehicle([_count(count), *(frame for _, frame in burst)])
    link = open_link(f"udpout:127.0.0.1:{fake.port}")
    try:
        client = MissionClient(
            link, target_system=1, target_component=1, timeout=0.2, item_timeout=0.05, retries=1
        )
        try:
            items = client.download()
        except LinkError:
            pass  # a clear refusal is a right answer to nonsense
        else:
            assert len(items) == count
            for item in items:
                struct.pack("<ii", item.x, item.y)  # what it returns fits the wire's integers
    finally:
        link.close()
        fake.close()
