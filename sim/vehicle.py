"""MockVehicle: a simulated fixed-wing autopilot on a MAVLink link.

It heartbeats at 1 Hz as a fixed-wing (component 1, ArduPilot or PX4 flavour), streams
MISSION_CURRENT at 1 Hz, and hands each message to the part that serves it: the mission protocol
(:mod:`sim.mission_server`: stores and serves missions as the autopilot does) and the parameters
(:mod:`sim.param_server`). Every handler runs under a guard: a message that makes one fail is
counted in ``handler_errors`` and the vehicle goes on answering.

It serves its firmware's parameters as shipped (:mod:`sim.param_server`, the records of
:mod:`gcs_planner.aircraft.autopilot`); :meth:`MockVehicle.autopilot_parameters` gives the flight
the
effective ones. MAV_CMD_MISSION_START and MAV_CMD_DO_SET_MODE to the mission mode (ArduPlane
AUTO, PX4 AUTO/MISSION: what MAVSDK's ``start_mission()`` sends) start the flight;
EXTENDED_SYS_STATE says landed (on the ground) until it starts, in the air while it plays, on
the ground after.

Faults (drop, duplicate, delay, reorder) can be injected on what it sends and on what it
receives. A frame that arrives again byte for byte (same MAVLink sequence number) from the same
address within ``DUPLICATE_WINDOW_S`` is dropped as a link-level duplicate, as a radio's
retransmission or a router's second path delivers it; a duplicate that differs in any byte is a
new message. The window and the address matter: a ground station restarted (a new process,
whose sequence numbers start again at 0) sends frames byte-identical to its predecessor's, and
those are new messages.

It runs in a thread: ``start()`` / ``stop()`` or ``with MockVehicle(...) as v:``. Given a
scenario it can fly its stored mission (``replay`` for the report, ``fly`` with telemetry).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterable
from typing import Any

from gcs_planner.sim import replay as replay_mod
from gcs_planner.sim import telemetry
from gcs_planner.sim.faults import FaultInjector, FaultRates
from gcs_planner.sim.ftp_server import FtpServer
from gcs_planner.sim.guidance import AutopilotParams
from gcs_planner.sim.mission_items import mission_protocol
from gcs_planner.sim.mission_server import MissionServer, seq_from_param
from gcs_planner.sim.param_server import ParamServer, parameter_table

from gcs_planner.aircraft.autopilot import (
    AUTOPILOTS,
    DEFAULT_AUTOPILOT,
    EffectiveParameters,
    autopilot_for,
)
from gcs_planner.link.connection import Link, mavlink
from gcs_planner.link.pacing import RadioFlow
from gcs_planner.mission.items import MissionItem
from gcs_planner.scenario.model import Scenario

FLAVOURS = tuple(AUTOPILOTS)  # the autopilots it can be (imported by the CLI and the dry run)
# Copies of one frame by a radio or a router arrive within milliseconds; a ground station
# resending on a timeout does so after its timeout (the link's: 1 s) with a new sequence number.
# Half a second tells the two apart on a busy machine.
DUPLICATE_WINDOW_S = 0.5
# A flight switched on board waits this long (wall seconds) for the ground station to cut the
# link once it has the start's acknowledgement, and is then cut off anyway.
CUT_WAIT_S = 5.0


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
        flavour: str = DEFAULT_AUTOPILOT,
        system_id: int = 1,
        component_id: int = 1,
        capacity: int = 5000,
        faults_out: FaultRates | None = None,
        faults_in: FaultRates | None = None,
        fault_seed: int = 0,
        signing_key: bytes | None = None,
        request_timeout: float | None = None,
        upload_timeout: float | None = None,
        heartbeat_period: float = 1.0,
        capture_radius: float = replay_mod.DEFAULT_CAPTURE_RADIUS_M,
        drop_link_duplicates: bool = True,
        baud: int = 57600,
        speedup: float | None = 100.0,
        live: bool = False,
        cruise_speedup: float | None = None,
        navigate_on_estimate: bool = True,
        wind: Any = None,
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
        # Live flights: the time scale while no failed or missed fix awaits the ground station
        # (None: ``speedup`` throughout; see sim/live_vehicle.py, "cruise").
        self.cruise_speedup = cruise_speedup
        # ... and the landmarks whose failed or missed fix the ground station acts on (None:
        # every one): elsewhere the flight keeps its cruise time scale.
        self.watch_points: frozenset[str] | None = None
        # Live: the flight is flown as it is played and follows missions uploaded and items set
        # current in flight (sim/live_vehicle.py), in ``wind`` (a sim.wind.WindModel), steering
        # its INS estimate or the truth.
        self.live = live
        self.navigate_on_estimate = navigate_on_estimate
        self.wind = wind
        self.last_live: Any = None  # the last live flight's sim.live_vehicle.LiveReport
        # Live, with an autopilot that runs Lua applets: the applet on its SD card (policy.lua's
        # text), which then switches the policy on board (sim/onboard_flight.py); and whether
        # its ground link is cut (nothing sent, nothing heard), as it is from that take-off on.
        self.applet: str | None = None
        self.link_cut = False
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
        self._inject_faults(faults_out, faults_in, fault_seed)
        self._home = self._home_position()
        self.autopilot = autopilot_for(flavour)
        self._serve(flavour, capacity, request_timeout, upload_timeout, baud)
        self.handler_errors = 0  # messages whose handling failed; the vehicle went on
        self.flight_errors = 0  # flights that raised; the vehicle said so and went on
        # (address, frame bytes) -> when it last arrived, for the duplicate window.
        self._seen: dict[tuple[Any, bytes], float] = {}
        self._seen_pruned = 0.0
        self.duplicates_dropped = 0  # frames dropped as link-level copies
        self.commands: list[tuple[int, int]] = []  # (MAV_CMD, MAV_RESULT) answered
        self._peers: set[tuple[int, int]] = set()  # ground stations heard
        self._peer_addresses: set[tuple[tuple[int, int], Any]] = set()
        self._thread: threading.Thread | None = None
        self._fly_thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._cut = threading.Event()  # the ground link was cut (cut_link)
        self.statustexts: list[str] = []  # what it announced, for tests and logs
        self.acks_sent = self.missions.acks_sent  # MAV_MISSION_RESULT of every MISSION_ACK
        self.last_report: replay_mod.ReplayReport | None = None
        self.flying = False  # HEARTBEAT says armed, mode AUTO while the flight plays
        self.flight_seed = 0  # seeds a live flight's draws (error directions, outcomes)
        # MAVFTP served and advertised (MAV_PROTOCOL_CAPABILITY_FTP); off, it is an ArduPilot
        # built without AP_MAVLINK_FTP_ENABLED, which ignores FILE_TRANSFER_PROTOCOL.
        self.ftp_enabled = True

    def _inject_faults(
        self, faults_out: FaultRates | None, faults_in: FaultRates | None, seed: int
    ) -> None:
        """Put the fault injectors on what it sends (under the packing writer) and receives."""
        self.faults_out: FaultInjector[bytes] | None = None
        self.faults_in: FaultInjector[Any] | None = None
        if faults_out is not None and faults_out.any:
            self.faults_out = FaultInjector(faults_out, seed)
            self.mav.file = _FaultyWriter(self.link.conn, self.faults_out, self._fault_lock)
        if faults_in is not None and faults_in.any:
            self.faults_in = FaultInjector(faults_in, seed + 1)

    def _serve(
        self,
        flavour: str,
        capacity: int,
        request_timeout: float | None,
        upload_timeout: float | None,
        baud: int,
    ) -> None:
        """The parts that serve its messages: missions, parameters, MAVLink FTP."""
        self.missions = MissionServer(
            self.mav,
            self._send,
            self._statustext,
            flavour=flavour,
            capacity=capacity,
            home=self._home,
            request_timeout=request_timeout,
            upload_timeout=upload_timeout,
            lock=self._lock,
        )
        profile = self.scenario.vehicle if self.scenario is not None else None
        table = parameter_table(flavour, profile)
        self.params = ParamServer(
            self.mav, self._send, table, self._lock, flavour=flavour, statustext=self._statustext
        )
        self.radio = RadioFlow()  # its telemetry radio's RADIO_STATUS, as ArduPilot reads it
        # MAVLink FTP (sim/ftp_server.py): ArduPilot serves its mission as @MISSION/mission.dat.
        self.ftp = FtpServer(
            self.mav, self._send, self.missions, flavour=flavour, baud=baud, radio=self.radio
        )

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

    def cut_link(self) -> None:
        """Cut the ground link: from now on the vehicle sends nothing and hears nothing."""
        self.link_cut = True
        self._cut.set()

    def request_stop(self) -> None:
        """Ask the loop to end at its next turn; safe from a signal handler."""
        self._stop.set()

    def serve_forever(self) -> None:
        """Run in the calling thread until ``stop()`` (from another thread) or Ctrl-C."""
        self._run()

    # What it holds ----------------------------------------------------------------------------
    @property
    def mission(self) -> list[MissionItem]:
        return self.missions.mission

    @property
    def parameters(self) -> dict[str, float]:
        return self.params.values

    def autopilot_parameters(self) -> EffectiveParameters:
        """The parameters the flight flies with now (shipped defaults, the scenario's aircraft,
        and whatever the ground station set): cruise airspeed, climb and sink rates, bank limit,
        loiter and acceptance radii, L1 (ArduPlane) or npfg (PX4) constants. See
        :class:`gcs_planner.aircraft.autopilot.EffectiveParameters`."""
        return self.params.effective

    @property
    def current(self) -> int:
        return self.missions.current

    # The flight sets the current item under ``_lock`` (shared with the mission server).
    @property
    def _current(self) -> int:
        return self.missions.current_seq

    @_current.setter
    def _current(self, seq: int) -> None:
        self.missions.current_seq = seq

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
        if not self.link_cut:
            self.link.send(msg)

    def _statustext(self, text: str, severity: int = mavlink.MAV_SEVERITY_INFO) -> None:
        self.statustexts.append(text)
        self._send(self.mav.statustext_encode(severity, text[:50].encode("ascii", "replace")))

    def _send_statustext_copy(self, text: str, severity: int = mavlink.MAV_SEVERITY_INFO) -> None:
        """A STATUSTEXT sent again (a correction report's copies): not logged twice."""
        self._send(self.mav.statustext_encode(severity, text[:50].encode("ascii", "replace")))

    def _heartbeat(self) -> None:
        fields = telemetry.heartbeat_fields(self.flavour, self.flying)
        self._send(self.mav.heartbeat_encode(*fields))
        self._extended_sys_state()

    def _extended_sys_state(self) -> None:
        # Both autopilots stream it (ArduPilot GCS_MAVLINK::send_extended_sys_state, PX4's
        # EXTENDED_SYS_STATE stream); MAVSDK's in_air and QGroundControl read landed_state.
        self._send(self.mav.extended_sys_state_encode(*telemetry.extended_sys_state(self.flying)))

    def _mission_current(self) -> None:
        self.missions.mission_current()

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
                self.missions.timers(now)
                self.ftp.timers(now)
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
        # Where it came from, kept with it through the fault injector's delays: a transfer is
        # bound to its sender's address as well as its ids.
        msg._gcs_address = self.link.last_sender
        if self.drop_link_duplicates and self._duplicate(msg, now):
            return ()
        if self.faults_in is not None:
            return self.faults_in.push(msg, now)
        return (msg,)

    def _duplicate(self, msg: Any, now: float) -> bool:
        """Whether ``msg`` is a copy of a frame from the same address within the window."""
        if now - self._seen_pruned > DUPLICATE_WINDOW_S:
            self._seen = {k: t for k, t in self._seen.items() if now - t <= DUPLICATE_WINDOW_S}
            self._seen_pruned = now
        key = (msg._gcs_address, bytes(msg.get_msgbuf()))
        seen = self._seen.get(key)
        self._seen[key] = now
        if seen is not None and now - seen <= DUPLICATE_WINDOW_S:
            self.duplicates_dropped += 1
            return True
        return False

    def _for_me(self, msg: Any) -> bool:
        ts = getattr(msg, "target_system", 0)
        tc = getattr(msg, "target_component", 0)
        return ts in (0, self.mav.srcSystem) and tc in (0, self.mav.srcComponent)

    # Handlers ---------------------------------------------------------------------------------
    def _handle(self, msg: Any) -> None:
        """Hand ``msg`` to what serves it. A failure in one handler is one lost answer, never
        the vehicle: it is counted and the loop goes on."""
        try:
            kind = msg.get_type()
            if self.link_cut or not self._for_me(msg):
                return
            peer = (msg.get_srcSystem(), msg.get_srcComponent())
            if kind in MissionServer.HANDLED:
                self.missions.handle(msg, peer, getattr(msg, "_gcs_address", None))
            elif kind in ParamServer.HANDLED:
                self.params.handle(msg, peer)
            elif kind == "HEARTBEAT":
                self._on_heartbeat(msg, peer)
            elif kind == "COMMAND_LONG":
                self._on_command_long(msg, peer)
            elif kind == "FILE_TRANSFER_PROTOCOL" and self.ftp_enabled:
                self.ftp.handle(msg, peer)
            elif kind == "RADIO_STATUS" and self.autopilot.reads_radio_status:
                # ArduPilot reads its own radio's reports (GCS_MAVLINK::handle_radio_status)
                # and waits that much longer before asking again for a mission item
                # (MissionItemProtocol::update: 1 s plus stream_slowdown_ms).
                self.radio.observe(msg)
                self.missions.request_slowdown = self.radio.extra_wait()
        except Exception:  # a hostile message must not end the vehicle
            self.handler_errors += 1

    def _on_heartbeat(self, msg: Any, peer: tuple[int, int]) -> None:
        # Answer a newcomer at once rather than at the next 1 Hz beat, as a vehicle listening on
        # udpin can only reach a ground station after hearing it. A newcomer is new ids or a new
        # address: a ground station restarted with the same ids (every `gcs-planner download`
        # is 255/190) otherwise waits up to a second for the next beat.
        key = (peer, getattr(msg, "_gcs_address", None))
        if key not in self._peer_addresses:
            self._peers.add(peer)
            self._peer_addresses.add(key)
            self._heartbeat()

    def _on_command_long(self, msg: Any, peer: tuple[int, int]) -> None:
        result = mavlink.MAV_RESULT_UNSUPPORTED
        if msg.command == mavlink.MAV_CMD_DO_SET_MISSION_CURRENT:
            seq = seq_from_param(msg.param1, len(self.mission))
            ok = seq is not None and self.missions.set_current(seq)
            if seq is None:
                self._statustext(f"Set current item {msg.param1!r} failed: no such item")
            result = mavlink.MAV_RESULT_ACCEPTED if ok else mavlink.MAV_RESULT_DENIED
        elif msg.command == mavlink.MAV_CMD_MISSION_START:
            result = self._start_flight()
        elif msg.command == mavlink.MAV_CMD_DO_SET_MODE:
            result = self._set_mode(msg.param1, msg.param2, msg.param3)
        elif msg.command == mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES or (
            msg.command == mavlink.MAV_CMD_REQUEST_MESSAGE
            and msg.param1 == mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION
        ):
            result = mavlink.MAV_RESULT_ACCEPTED
        self.commands.append((int(msg.command), result))
        self._send(self.mav.command_ack_encode(msg.command, result))
        if result == mavlink.MAV_RESULT_ACCEPTED and msg.command in (
            mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
            mavlink.MAV_CMD_REQUEST_MESSAGE,
        ):
            self._autopilot_version()

    def _autopilot_version(self) -> None:
        """AUTOPILOT_VERSION with the capabilities each autopilot sets: ArduPilot's
        ``GCS_MAVLINK::capabilities`` (GCS_Common.cpp: MAVLink 2, MISSION_INT, COMMAND_INT,
        PARAM_FLOAT, fence and rally missions, FTP where AP_MAVLINK_FTP_ENABLED), PX4's
        ``Mavlink::send_autopilot_capabilities`` (mavlink_main.cpp: the same with MISSION_FLOAT,
        FTP among them, though PX4 serves no @MISSION file)."""
        cap = (
            mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
            | mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_INT
            | mavlink.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
            | mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
            | mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
            | mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_RALLY
            | mavlink.MAV_PROTOCOL_CAPABILITY_FTP
        )
        if mission_protocol(self.flavour).announces_mission_float:
            cap |= mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT
        if not self.ftp_enabled:
            cap &= ~mavlink.MAV_PROTOCOL_CAPABILITY_FTP
        self._send(
            self.mav.autopilot_version_encode(cap, 0, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0, 0, 0)
        )

    def _set_mode(self, base: float, main: float, sub: float) -> int:
        """MAV_CMD_DO_SET_MODE. The mission mode starts the flight as MISSION_START does (what
        ArduPlane's AUTO and PX4's AUTO/MISSION do once airborne); this mock models no other
        mode, and refuses one as ArduPilot refuses a mode it cannot enter
        (``GCS_MAVLINK::_set_mode_common``: MAV_RESULT_FAILED) or PX4 a transition it denies
        (``Commander::handle_command``: MAV_RESULT_TEMPORARILY_REJECTED)."""
        if self.autopilot.is_auto_mode(base, main, sub):
            return self._start_flight()
        self._statustext("Mode change refused: only the mission mode is modelled")
        if self.autopilot.refuses_mode_temporarily:
            return mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        custom = math.isfinite(base) and int(base) & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
        # ArduPilot: no custom-mode flag is an invalid command (DENIED); a custom mode it cannot
        # enter is FAILED.
        return mavlink.MAV_RESULT_FAILED if custom else mavlink.MAV_RESULT_DENIED

    def _start_flight(self) -> int:
        if self._fly_thread is not None and self._fly_thread.is_alive():
            # Already flying the mission: MAVSDK's start_mission() on ArduPilot sends
            # DO_SET_MODE AUTO and then MISSION_START; both autopilots accept the second while
            # in the mission mode. The flight under way goes on; none is started beside it.
            return mavlink.MAV_RESULT_ACCEPTED
        home_only = 1 if self.autopilot.home_at_seq0 else 0  # ArduPilot's home stays
        if self.scenario is None or len(self.mission) <= home_only:
            return mavlink.MAV_RESULT_DENIED
        self._fly_thread = threading.Thread(target=self._fly_guarded, daemon=True)
        self._fly_thread.start()
        return mavlink.MAV_RESULT_ACCEPTED

    def _fly_guarded(self) -> None:
        """The flight thread: whatever the flight model raises ends this flight with a
        STATUSTEXT, never the vehicle (which goes on answering and can fly again)."""
        try:
            if self.live and self.applet is not None and self.autopilot.runs_lua_applets:
                from gcs_planner.sim.onboard_flight import fly_onboard

                # Take-off is when the ground station, its start acknowledged, cuts the link
                # (or, if it never does, after CUT_WAIT_S): the simulated clock starts there.
                self._cut.wait(CUT_WAIT_S)
                fly_onboard(self, seed=self.flight_seed)
            elif self.live:
                from gcs_planner.sim.live_vehicle import fly_live

                fly_live(self, seed=self.flight_seed, time_scale=self.speedup)
            else:
                self.fly(time_scale=self.speedup)
        except Exception as exc:
            self.flight_errors += 1
            self.flying = False
            self._heartbeat()
            text = f"Flight aborted: {type(exc).__name__}"
            self._statustext(text, mavlink.MAV_SEVERITY_CRITICAL)

    # Flying -----------------------------------------------------------------------------------
    @property
    def cruise_speed(self) -> float:
        return self.autopilot_parameters().cruise_airspeed

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
            home_at_seq0=self.autopilot.home_at_seq0,
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
            self._heartbeat()  # disarmed and on the ground at once, not at the next beat
        return report

    def _fly_current(self, seq: int) -> None:
        with self._lock:
            self._current = seq
        self._mission_current()


def free_udp_port() -> int:
    """A UDP port on 127.0.0.1 that nothing holds right now."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])
