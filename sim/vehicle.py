"""MockVehicle: the vehicle side of the MAVLink mission protocol, as an autopilot behaves.

It heartbeats at 1 Hz as a fixed-wing (component 1, ArduPilot or PX4 flavour), stores missions
it is sent (ArduPilot flavour keeps its home in item 0, as ArduPilot does), serves them back,
streams MISSION_CURRENT at 1 Hz, answers parameter reads and writes, and refuses what an
autopilot refuses with the right MAV_MISSION_RESULT. Transfers time out as ArduPilot's do: an
item not received within ``request_timeout`` is asked for again, and an upload with no item for
``upload_timeout`` is cancelled. It never waits for the final MISSION_ACK of a download.

Faults (drop, duplicate, delay, reorder) can be injected on what it sends and on what it
receives. Frames that arrive twice byte for byte (same MAVLink sequence number) are dropped as
link-level duplicates, a check real radios and routers also make; a duplicate that differs in
any byte is a new message and handled as such.

It runs in a thread: ``start()`` / ``stop()`` or ``with MockVehicle(...) as v:``. Given a
scenario it can fly its stored mission (``replay`` for the report, ``fly`` with telemetry).
"""

from __future__ import annotations

import collections
import math
import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from gcs_planner.link.connection import Link, mavlink
from gcs_planner.link.protocol import item_from_message, item_to_message
from gcs_planner.mission.items import MAV_MISSION_TYPE_MISSION, MissionItem
from gcs_planner.scenario.model import Scenario
from sim import replay as replay_mod
from sim import telemetry
from sim.faults import FaultInjector, FaultRates
from sim.guidance import AutopilotParams

FLAVOURS = ("ardupilot", "px4")
_AUTOPILOT = {
    "ardupilot": mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
    "px4": mavlink.MAV_AUTOPILOT_PX4,
}
SUPPORTED_FRAMES = frozenset({0, 2, 3, 5, 6})
SUPPORTED_COMMANDS = frozenset(
    {16, 17, 18, 19, 20, 21, 22, 31, 112, 113, 114, 115, 176, 177, 178, 179, 183, 184, 189, 201}
)
POSITION_COMMANDS = replay_mod.NAV_POSITION_COMMANDS
ALT_RANGE_M = (-1000.0, 100_000.0)


@dataclass
class _Upload:
    """An upload in progress (the vehicle is receiving)."""

    peer: tuple[int, int]
    count: int
    items: list[MissionItem]
    last_receive: float
    last_request: float

    @property
    def expected(self) -> int:
        return len(self.items)


def _param_table(flavour: str, turn_radius: float | None) -> dict[str, tuple[float, int]]:
    r = 80.0 if turn_radius is None else float(turn_radius)
    if flavour == "ardupilot":
        return {
            "WP_LOITER_RAD": (float(round(r)), mavlink.MAV_PARAM_TYPE_INT16),
            "WP_RADIUS": (90.0, mavlink.MAV_PARAM_TYPE_INT16),
            "AIRSPEED_CRUISE": (replay_mod.DEFAULT_CRUISE_SPEED, mavlink.MAV_PARAM_TYPE_REAL32),
        }
    return {
        "NAV_LOITER_RAD": (r, mavlink.MAV_PARAM_TYPE_REAL32),
        "NAV_ACC_RAD": (10.0, mavlink.MAV_PARAM_TYPE_REAL32),
        "FW_AIRSPD_TRIM": (replay_mod.DEFAULT_CRUISE_SPEED, mavlink.MAV_PARAM_TYPE_REAL32),
    }


_CRUISE_PARAM = {"ardupilot": "AIRSPEED_CRUISE", "px4": "FW_AIRSPD_TRIM"}


class _FaultyWriter:
    """Stands in for the connection as pymavlink's writer so every packed frame goes through the
    outgoing fault injector."""

    def __init__(self, conn: Any, injector: FaultInjector[bytes], lock: threading.Lock) -> None:
        self.conn = conn
        self.injector = injector
        self.lock = lock

    def write(self, buf: bytes) -> None:
        with self.lock:
            frames = self.injector.push(bytes(buf), time.monotonic())
        for frame in frames:
            self.conn.write(frame)


class MockVehicle:
    """A simulated fixed-wing autopilot on ``connection`` (a pymavlink connection string)."""

    def __init__(
        self,
        connection: str,
        *,
        scenario: Scenario | None = None,
        flavour: str = "ardupilot",
        system_id: int = 1,
        component_id: int = 1,
        capacity: int = 5000,
        faults_out: FaultRates | None = None,
        faults_in: FaultRates | None = None,
        fault_seed: int = 0,
        signing_key: bytes | None = None,
        request_timeout: float = 1.0,
        upload_timeout: float = 8.0,
        heartbeat_period: float = 1.0,
        capture_radius: float = replay_mod.DEFAULT_CAPTURE_RADIUS_M,
        drop_link_duplicates: bool = True,
        baud: int = 57600,
        speedup: float | None = 100.0,
    ) -> None:
        if flavour not in FLAVOURS:
            raise ValueError(f"flavour must be one of {FLAVOURS}, got {flavour!r}")
        if capacity < 0:
            raise ValueError("capacity must be >= 0")
        self.flavour = flavour
        self.scenario = scenario
        self.capacity = capacity
        self.request_timeout = request_timeout
        self.upload_timeout = upload_timeout
        self.heartbeat_period = heartbeat_period
        self.capture_radius = capture_radius
        self.drop_link_duplicates = drop_link_duplicates
        # Simulated seconds per wall second of a flight started by MISSION_START (1: real time,
        # None: fast-forward).
        self.speedup = speedup
        self.link = Link(
            connection,
            baud=baud,
            source_system=system_id,
            source_component=component_id,
            signing_key=signing_key,
        )
        self.mav = self.link.mav
        self._lock = threading.Lock()  # guards mission, params, current
        self._fault_lock = threading.Lock()
        self.faults_out: FaultInjector[bytes] | None = None
        self.faults_in: FaultInjector[Any] | None = None
        if faults_out is not None and faults_out.any:
            self.faults_out = FaultInjector(faults_out, fault_seed)
            self.mav.file = _FaultyWriter(self.link.conn, self.faults_out, self._fault_lock)
        if faults_in is not None and faults_in.any:
            self.faults_in = FaultInjector(faults_in, fault_seed + 1)
        turn_radius = scenario.params.turn_radius if scenario is not None else None
        self._params = _param_table(flavour, turn_radius)
        self._mission: list[MissionItem] = []
        self._current = 0
        self._upload: _Upload | None = None
        # (peer, count) of the last upload completed: its final item may come again when the
        # ground station missed the acknowledgement, and is answered with it again.
        self._completed: tuple[tuple[int, int], int] | None = None
        self._seen: collections.deque[bytes] = collections.deque(maxlen=64)
        self._seen_set: set[bytes] = set()
        self._peers: set[tuple[int, int]] = set()
        self._thread: threading.Thread | None = None
        self._fly_thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.statustexts: list[str] = []  # what it announced, for tests and logs
        self.acks_sent: list[int] = []  # MAV_MISSION_RESULT of every MISSION_ACK it sent
        self.last_report: replay_mod.ReplayReport | None = None
        self.flying = False  # HEARTBEAT says armed, mode AUTO while the flight plays
        self._home = self._home_position()

    # Lifecycle --------------------------------------------------------------------------------
    def start(self) -> MockVehicle:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="mock-vehicle", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        for t in (self._fly_thread, self._thread):
            if t is not None:
                t.join(timeout=5.0)
        self._thread = None
        self.link.close()

    def __enter__(self) -> MockVehicle:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def request_stop(self) -> None:
        """Ask the loop to end at its next turn; safe from a signal handler."""
        self._stop.set()

    def serve_forever(self) -> None:
        """Run in the calling thread until ``stop()`` (from another thread) or Ctrl-C."""
        self._run()

    # What it holds ----------------------------------------------------------------------------
    @property
    def mission(self) -> list[MissionItem]:
        with self._lock:
            return list(self._mission)

    @property
    def parameters(self) -> dict[str, float]:
        with self._lock:
            return {k: v for k, (v, _) in self._params.items()}

    @property
    def current(self) -> int:
        with self._lock:
            return self._current

    @property
    def refused_signature(self) -> int:
        return self.link.refused_signature

    def _home_position(self) -> tuple[int, int, float]:
        if self.scenario is None:
            o = replay_mod.DEFAULT_ORIGIN
            return round(o.lat * 1e7), round(o.lon * 1e7), o.alt
        frame = replay_mod.scenario_frame(self.scenario)
        lat, lon, alt = frame.to_geodetic(*self.scenario.xyz[self.scenario.start])
        return round(lat * 1e7), round(lon * 1e7), float(alt)

    # Sending ----------------------------------------------------------------------------------
    def _send(self, msg: Any) -> None:
        self.link.send(msg)

    def _ack(self, peer: tuple[int, int], result: int, mission_type: int = 0) -> None:
        self.acks_sent.append(result)
        self._send(self.mav.mission_ack_encode(peer[0], peer[1], result, mission_type))

    def _statustext(self, text: str, severity: int = mavlink.MAV_SEVERITY_INFO) -> None:
        self.statustexts.append(text)
        self._send(self.mav.statustext_encode(severity, text[:50].encode("ascii", "replace")))

    def _heartbeat(self) -> None:
        fields = telemetry.heartbeat_fields(self.flavour, self.flying)
        self._send(self.mav.heartbeat_encode(*fields))

    def _mission_current(self) -> None:
        with self._lock:
            seq, total = self._current, len(self._mission)
        self._send(self.mav.mission_current_encode(seq, total))

    # The loop ---------------------------------------------------------------------------------
    def _run(self) -> None:
        next_beat = 0.0
        next_current = 0.0
        try:
            while not self._stop.is_set():
                now = time.monotonic()
                if now >= next_beat:
                    self._heartbeat()
                    next_beat = now + self.heartbeat_period
                if now >= next_current:
                    self._mission_current()
                    next_current = now + 1.0
                self._transfer_timers(now)
                self._release_held(now)
                msg = self.link.recv(0.01)
                if msg is None:
                    continue
                for m in self._incoming(msg, time.monotonic()):
                    self._handle(m)
        except KeyboardInterrupt:
            pass

    def _release_held(self, now: float) -> None:
        if self.faults_out is not None:
            with self._fault_lock:
                frames = self.faults_out.due(now)
            for frame in frames:
                self.link.write_raw(frame)
        if self.faults_in is not None:
            for m in self.faults_in.due(now):
                self._handle(m)

    def _incoming(self, msg: Any, now: float) -> Iterable[Any]:
        if self.drop_link_duplicates:
            key = bytes(msg.get_msgbuf())
            if key in self._seen_set:
                return ()
            if len(self._seen) == self._seen.maxlen:
                self._seen_set.discard(self._seen[0])
            self._seen.append(key)
            self._seen_set.add(key)
        if self.faults_in is not None:
            return self.faults_in.push(msg, now)
        return (msg,)

    def _transfer_timers(self, now: float) -> None:
        up = self._upload
        if up is None:
            return
        if now - up.last_receive > self.upload_timeout:
            self._upload = None
            self._ack(up.peer, mavlink.MAV_MISSION_OPERATION_CANCELLED)
            self._statustext("Mission upload timed out", mavlink.MAV_SEVERITY_WARNING)
        elif now - up.last_request > self.request_timeout:
            self._request(up, now)

    def _request(self, up: _Upload, now: float) -> None:
        up.last_request = now
        self._send(
            self.mav.mission_request_int_encode(
                up.peer[0], up.peer[1], up.expected, MAV_MISSION_TYPE_MISSION
            )
        )

    def _for_me(self, msg: Any) -> bool:
        ts = getattr(msg, "target_system", 0)
        tc = getattr(msg, "target_component", 0)
        return ts in (0, self.mav.srcSystem) and tc in (0, self.mav.srcComponent)

    # Handlers ---------------------------------------------------------------------------------
    def _handle(self, msg: Any) -> None:
        kind = msg.get_type()
        handler = getattr(self, f"_on_{kind.lower()}", None)
        if handler is None or not self._for_me(msg):
            return
        handler(msg, (msg.get_srcSystem(), msg.get_srcComponent()))

    def _on_heartbeat(self, msg: Any, peer: tuple[int, int]) -> None:
        # Answer a newcomer at once rather than at the next 1 Hz beat, as a vehicle listening on
        # udpin can only reach a ground station after hearing it.
        if peer not in self._peers:
            self._peers.add(peer)
            self._heartbeat()

    def _on_mission_count(self, msg: Any, peer: tuple[int, int]) -> None:
        mtype = getattr(msg, "mission_type", 0)
        if mtype != MAV_MISSION_TYPE_MISSION:
            self._ack(peer, mavlink.MAV_MISSION_UNSUPPORTED, mtype)
            return
        if self._upload is not None and self._upload.peer != peer:
            self._ack(peer, mavlink.MAV_MISSION_DENIED)
            return
        self._upload = None  # the same sender may restart (ArduPilot does the same)
        self._completed = None
        if msg.count > self.capacity:
            self._ack(peer, mavlink.MAV_MISSION_NO_SPACE)
            self._statustext(f"Only {self.capacity} items are supported")
            return
        now = time.monotonic()
        if msg.count == 0:
            self._commit([])
            self._ack(peer, mavlink.MAV_MISSION_ACCEPTED)
            return
        self._upload = _Upload(peer, int(msg.count), [], now, now)
        self._request(self._upload, now)

    def _on_mission_item_int(self, msg: Any, peer: tuple[int, int]) -> None:
        up = self._upload
        if up is None or getattr(msg, "mission_type", 0) != MAV_MISSION_TYPE_MISSION:
            if up is None and self._completed == (peer, msg.seq + 1):
                # The final item resent: the acknowledgement was lost (PX4 answers the same).
                self._ack(peer, mavlink.MAV_MISSION_ACCEPTED)
            return  # otherwise a late copy of an item from a finished transfer
        if peer != up.peer:
            self._ack(peer, mavlink.MAV_MISSION_DENIED)
            return
        if msg.seq != up.expected:
            self._ack(peer, mavlink.MAV_MISSION_INVALID_SEQUENCE)
            return
        item = item_from_message(msg)
        result = self._check_item(item)
        if result != mavlink.MAV_MISSION_ACCEPTED:
            self._upload = None
            self._ack(peer, result)
            return
        now = time.monotonic()
        up.items.append(item)
        up.last_receive = now
        if up.expected == up.count:
            self._upload = None
            self._completed = (peer, up.count)
            self._commit(up.items)
            self._ack(peer, mavlink.MAV_MISSION_ACCEPTED)
            self._mission_current()
        else:
            self._request(up, now)

    _on_mission_item = _on_mission_item_int

    def _check_item(self, item: MissionItem) -> int:
        if item.frame not in SUPPORTED_FRAMES:
            return mavlink.MAV_MISSION_UNSUPPORTED_FRAME
        if item.command not in SUPPORTED_COMMANDS:
            return mavlink.MAV_MISSION_UNSUPPORTED
        if item.command in POSITION_COMMANDS and item.frame != 2:
            if not -900_000_000 <= item.x <= 900_000_000:
                return mavlink.MAV_MISSION_INVALID_PARAM5_X
            if not -1_800_000_000 <= item.y <= 1_800_000_000:
                return mavlink.MAV_MISSION_INVALID_PARAM6_Y
            if not (math.isfinite(item.z) and ALT_RANGE_M[0] <= item.z <= ALT_RANGE_M[1]):
                return mavlink.MAV_MISSION_INVALID_PARAM7
        return mavlink.MAV_MISSION_ACCEPTED

    def _commit(self, items: list[MissionItem]) -> None:
        items = [MissionItem(**{**_fields(it), "current": 0}) for it in items]
        if self.flavour == "ardupilot" and items:
            # ArduPilot keeps its own home in item 0 whatever the ground station sent there.
            lat, lon, alt = self._home
            items[0] = MissionItem(0, 0, 16, 0, 1, 0.0, 0.0, 0.0, 0.0, lat, lon, alt)
        with self._lock:
            self._mission = items
            self._current = 1 if self.flavour == "ardupilot" and len(items) > 1 else 0

    def _on_mission_request_list(self, msg: Any, peer: tuple[int, int]) -> None:
        mtype = getattr(msg, "mission_type", 0)
        if self._upload is not None:
            self._ack(peer, mavlink.MAV_MISSION_DENIED, mtype)
            return
        count = len(self.mission) if mtype == MAV_MISSION_TYPE_MISSION else 0
        self._send(self.mav.mission_count_encode(peer[0], peer[1], count, mtype))

    def _on_mission_request_int(self, msg: Any, peer: tuple[int, int]) -> None:
        mtype = getattr(msg, "mission_type", 0)
        if self._upload is not None:
            self._ack(peer, mavlink.MAV_MISSION_DENIED, mtype)
            return
        mission = self.mission if mtype == MAV_MISSION_TYPE_MISSION else []
        if not 0 <= msg.seq < len(mission):
            self._ack(peer, mavlink.MAV_MISSION_INVALID_SEQUENCE, mtype)
            return
        item = mission[msg.seq]
        if msg.seq == self.current:
            item = MissionItem(**{**_fields(item), "current": 1})
        self._send(item_to_message(self.mav, item, peer[0], peer[1]))

    # The deprecated request is answered with MISSION_ITEM_INT too, as the specification asks.
    _on_mission_request = _on_mission_request_int

    def _on_mission_ack(self, msg: Any, peer: tuple[int, int]) -> None:
        up = self._upload
        if up is not None and peer == up.peer and msg.type != mavlink.MAV_MISSION_ACCEPTED:
            self._upload = None  # the ground station cancelled the upload

    def _on_mission_clear_all(self, msg: Any, peer: tuple[int, int]) -> None:
        mtype = getattr(msg, "mission_type", 0)
        if self._upload is not None:
            self._ack(peer, mavlink.MAV_MISSION_ERROR, mtype)
            return
        if mtype == MAV_MISSION_TYPE_MISSION:
            self._commit([])
        self._ack(peer, mavlink.MAV_MISSION_ACCEPTED, mtype)

    def _set_current(self, seq: int) -> bool:
        with self._lock:
            if not 0 <= seq < len(self._mission):
                ok = False
            else:
                self._current = seq
                ok = True
        if ok:
            self._mission_current()
        else:
            self._statustext(f"Set current item {seq} failed: no such item")
        return ok

    def _on_mission_set_current(self, msg: Any, peer: tuple[int, int]) -> None:
        self._set_current(int(msg.seq))

    def _on_command_long(self, msg: Any, peer: tuple[int, int]) -> None:
        result = mavlink.MAV_RESULT_UNSUPPORTED
        if msg.command == mavlink.MAV_CMD_DO_SET_MISSION_CURRENT:
            ok = self._set_current(int(msg.param1))
            result = mavlink.MAV_RESULT_ACCEPTED if ok else mavlink.MAV_RESULT_DENIED
        elif msg.command == mavlink.MAV_CMD_MISSION_START:
            busy = self._fly_thread is not None and self._fly_thread.is_alive()
            if self.scenario is None or not self.mission or busy:
                result = mavlink.MAV_RESULT_DENIED
            else:
                result = mavlink.MAV_RESULT_ACCEPTED
                self._fly_thread = threading.Thread(
                    target=self.fly, kwargs={"time_scale": self.speedup}, daemon=True
                )
                self._fly_thread.start()
        self._send(self.mav.command_ack_encode(msg.command, result))

    # Parameters -------------------------------------------------------------------------------
    def _param_value(self, name: str) -> None:
        with self._lock:
            names = list(self._params)
            value, ptype = self._params[name]
        self._send(
            self.mav.param_value_encode(
                name.encode("ascii"), value, ptype, len(names), names.index(name)
            )
        )

    def _on_param_set(self, msg: Any, peer: tuple[int, int]) -> None:
        name = _param_name(msg.param_id)
        with self._lock:
            if name not in self._params:
                return  # autopilots stay silent about parameters they do not have
            _, ptype = self._params[name]
            value = float(msg.param_value)
            if ptype != mavlink.MAV_PARAM_TYPE_REAL32:
                value = float(round(value))
            if math.isfinite(value):
                self._params[name] = (value, ptype)
        self._param_value(name)

    def _on_param_request_read(self, msg: Any, peer: tuple[int, int]) -> None:
        name = _param_name(msg.param_id)
        with self._lock:
            names = list(self._params)
        if msg.param_index >= 0:
            if msg.param_index >= len(names):
                return
            name = names[msg.param_index]
        if name in names:
            self._param_value(name)

    def _on_param_request_list(self, msg: Any, peer: tuple[int, int]) -> None:
        with self._lock:
            names = list(self._params)
        for name in names:
            self._param_value(name)

    # Flying -----------------------------------------------------------------------------------
    @property
    def cruise_speed(self) -> float:
        return self.parameters[_CRUISE_PARAM[self.flavour]]

    def replay(self, *, seed: int = 0, runs: int = 0) -> replay_mod.ReplayReport:
        """Fly the stored mission in mode AUTO (sim/guidance.py) with the landmark database's
        vehicle profile and this vehicle's parameters, and replay the INS (no telemetry)."""
        if self.scenario is None:
            raise RuntimeError("the mock vehicle was started without a scenario to fly in")
        report = replay_mod.replay(
            self.mission,
            self.scenario,
            seed=seed,
            runs=runs,
            home_at_seq0=self.flavour == "ardupilot",
            capture_radius=self.capture_radius,
            cruise_speed=self.cruise_speed,
            flavour=self.flavour,
            autopilot=AutopilotParams.from_parameters(self.flavour, self.parameters),
        )
        self.last_report = report
        return report

    def fly(
        self, *, seed: int = 0, time_scale: float | None = None, position_messages: int = 100
    ) -> replay_mod.ReplayReport:
        """Fly and send the telemetry (sim/telemetry.py): HEARTBEAT armed in AUTO,
        GLOBAL_POSITION_INT, ATTITUDE, VFR_HUD, MISSION_CURRENT, MISSION_ITEM_REACHED and a
        STATUSTEXT at each correction and on loss. ``time_scale``: simulated seconds per wall
        second; None sends the whole flight at once with at most ``position_messages``
        positions."""
        report = self.replay(seed=seed)
        assert self.scenario is not None
        self.flying = True
        self._heartbeat()
        try:
            telemetry.play(
                report,
                replay_mod.scenario_frame(self.scenario),
                self._send,
                self.mav,
                statustext=self._statustext,
                set_current=self._fly_current,
                stop=self._stop,
                time_scale=time_scale,
                max_positions=position_messages,
            )
        finally:
            self.flying = False
        return report

    def _fly_current(self, seq: int) -> None:
        with self._lock:
            self._current = seq
        self._mission_current()


def _fields(item: MissionItem) -> dict[str, Any]:
    return {f: getattr(item, f) for f in item.__dataclass_fields__}


def _param_name(pid: Any) -> str:
    if isinstance(pid, bytes):
        pid = pid.decode("ascii", "replace")
    return str(pid).rstrip("\x00")


def free_udp_port() -> int:
    """A UDP port on 127.0.0.1 that nothing holds right now."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])
