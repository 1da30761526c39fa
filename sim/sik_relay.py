"""The SiK radio pair as a UDP relay between a ground station and the mock vehicle: the event
loop that runs both radios in simulated time, their serial lines, their TDM turns on the one
air channel, and the RADIO_STATUS each writes to its host (:mod:`sim.radio` describes the whole
model and what it leaves out).
"""

from __future__ import annotations

import heapq
import itertools
import random
import select
import threading
import time
from collections.abc import Callable

from gcs_planner.sim.sik_config import TRAILER_BYTES, GilbertElliott, RadioConfig, Timing
from gcs_planner.sim.sik_serial import (
    NOISE,
    RSSI_BAD,
    RSSI_GOOD,
    FramePiece,
    RadioCounts,
    RadioEnd,
    is_heartbeat,
    udp_endpoint,
)

from gcs_planner.link.connection import mavlink

# SiK's MAVLink report comes from system '3', component 'D' (mavlink.c: RADIO_SOURCE_SYSTEM).
RADIO_SYSTEM = 51
RADIO_COMPONENT = 68
STATISTICS_BYTES = 4  # tdm.c: struct statistics (average rssi and noise, receive count)
LINK_UPDATE_S = 0.5  # tdm.c: link_update every 32,768 ticks


class SikRadio:
    """The radio pair as a relay: ``ground`` is where the ground station connects, ``vehicle``
    where the vehicle is (see :func:`udp_endpoint` for the forms). Runs in a thread:
    ``start()`` / ``stop()`` or ``with SikRadio(...) as radio:``."""

    def __init__(
        self,
        ground: str,
        vehicle: str,
        config: RadioConfig | None = None,
        *,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.config = config or RadioConfig()
        self.timing = Timing.of(self.config)
        self.clock = clock
        gsock, gpeer, glisten = udp_endpoint(ground)
        try:
            vsock, vpeer, vlisten = udp_endpoint(vehicle)
        except BaseException:
            gsock.close()
            raise
        self.ground = RadioEnd("ground", gsock, gpeer, glisten)
        self.air = RadioEnd("air", vsock, vpeer, vlisten)
        self.counts = RadioCounts()
        self._channel = GilbertElliott(self.config.loss, self.config.burst, self.config.seed)
        self._jitter = random.Random(self.config.seed + 1)
        self._fades: list[tuple[float, float]] = []
        self._events: list[tuple[float, int, Callable[[float], None]]] = []
        self._order = itertools.count()
        self._mav = mavlink.MAVLink(None, RADIO_SYSTEM, RADIO_COMPONENT)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._started = False

    # Where to connect -------------------------------------------------------------------------
    @property
    def ground_address(self) -> tuple[str, int]:
        host, port = self.ground.sock.getsockname()[:2]
        return str(host), int(port)

    @property
    def ground_connection(self) -> str:
        """The connection string a ground station uses to reach the ground radio."""
        host, port = self.ground_address
        return f"udpout:{'127.0.0.1' if host == '0.0.0.0' else host}:{port}"

    @property
    def vehicle_connection(self) -> str:
        """The connection string a vehicle uses to reach the air radio when the air end listens
        (``udpin``): it sends to it, as an autopilot writes to its radio's serial port."""
        host, port = self.air.sock.getsockname()[:2]
        return f"udpout:{'127.0.0.1' if host == '0.0.0.0' else host}:{port}"

    # Lifecycle --------------------------------------------------------------------------------
    def start(self) -> SikRadio:
        if self._thread is None:
            self._begin(self.clock())
            self._thread = threading.Thread(target=self._run, name="sik-radio", daemon=True)
            self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        for end in (self.ground, self.air):
            end.sock.close()

    def __enter__(self) -> SikRadio:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def serve_forever(self) -> None:
        """Run in the calling thread until :meth:`request_stop` (or Ctrl-C)."""
        self._begin(self.clock())
        try:
            self._run()
        except KeyboardInterrupt:
            pass

    def request_stop(self) -> None:
        self._stop.set()

    def fade(self, seconds: float, *, after: float = 0.0) -> None:
        """Lose every air packet for ``seconds``, starting ``after`` seconds from now."""
        now = self.clock()
        with self._lock:
            self._fades.append((now + after, now + after + seconds))

    def txbuf(self, end: str = "ground") -> int:
        """The ``txbuf`` the ``end`` radio reports now (percent free of its serial-in buffer)."""
        radio = self.ground if end == "ground" else self.air
        with self._lock:
            return self._txbuf(radio)

    # The event loop ---------------------------------------------------------------------------
    def _begin(self, now: float) -> None:
        if self._started:
            return
        self._started = True
        self._window_start(now, self.ground)
        self._at(now + LINK_UPDATE_S, self._link_update)

    def _at(self, when: float, action: Callable[[float], None]) -> None:
        heapq.heappush(self._events, (when, next(self._order), action))

    def _run(self) -> None:
        socks = [self.ground.sock, self.air.sock]
        while not self._stop.is_set():
            now = self.clock()
            with self._lock:
                # Events run in their own (simulated) order and time, even when this thread is
                # late: a late thread delays delivery, never reorders or speeds up the air.
                while self._events and self._events[0][0] <= now:
                    when, _, action = heapq.heappop(self._events)
                    action(when)
                wait = self._events[0][0] - now if self._events else 0.05
            try:
                ready, _, _ = select.select(socks, [], [], max(0.0, min(wait, 0.05)))
            except (OSError, ValueError):
                return  # the sockets were closed under us: stopping
            for sock in ready:
                end = self.ground if sock is self.ground.sock else self.air
                self._drain_socket(end)

    def _drain_socket(self, end: RadioEnd) -> None:
        while True:
            try:
                data, sender = end.sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return  # ICMP port unreachable from a host not there yet, or closed
            if end.listening:
                end.peer = sender
            elif sender != end.peer:
                continue
            with self._lock:
                self._from_host(end, bytes(data), self.clock())

    # The serial side --------------------------------------------------------------------------
    def _serial_s(self, nbytes: int) -> float:
        return nbytes * 10 / self.config.serial_baud

    def _from_host(self, end: RadioEnd, frame: bytes, now: float) -> None:
        # The host's bytes queue on its serial line and reach the radio at the serial rate.
        start = max(now, end.line_in_free)
        done = start + self._serial_s(len(frame))
        end.line_in_free = done
        self._at(done, lambda t: self._into_radio(end, frame))

    def _into_radio(self, end: RadioEnd, frame: bytes) -> None:
        if end.serial_in_used + len(frame) > self.config.serial_in_bytes:
            self.counts.serial_in_drops += 1
            return
        end.serial_in.append(FramePiece(frame))
        end.serial_in_used += len(frame)

    def _to_host(self, end: RadioEnd, frame: bytes, now: float) -> bool:
        """Queue ``frame`` in ``end``'s serial-out buffer; False when it does not fit."""
        if end.serial_out_used + len(frame) > self.config.serial_out_bytes:
            return False
        end.serial_out.append(frame)
        end.serial_out_used += len(frame)
        if not end.line_out_busy:
            end.line_out_busy = True
            self._at(now + self._serial_s(len(frame)), lambda t: self._line_out_done(end, t))
        return True

    def _line_out_done(self, end: RadioEnd, now: float) -> None:
        frame = end.serial_out.popleft()
        end.serial_out_used -= len(frame)
        if end.peer is not None:
            try:
                end.sock.sendto(frame, end.peer)
            except OSError:
                pass  # nothing listens there (yet): the bytes fall off the serial line
        if end.serial_out:
            nxt = now + self._serial_s(len(end.serial_out[0]))
            self._at(nxt, lambda t: self._line_out_done(end, t))
        else:
            end.line_out_busy = False

    def _txbuf(self, end: RadioEnd) -> int:
        size = self.config.serial_in_bytes
        free = size - end.serial_in_used
        return (100 * (free // 8)) // (size // 8)

    def _report(self, end: RadioEnd, now: float) -> None:
        """MAVLink_report: a RADIO_STATUS to this radio's host."""
        msg = self._mav.radio_status_encode(
            min(255, int(end.rssi)),
            min(255, end.remote_rssi),
            self._txbuf(end),
            min(255, int(end.noise)),
            min(255, end.remote_noise),
            min(0xFFFF, end.rx_errors),
            0,
        )
        if self._to_host(end, bytes(msg.pack(self._mav)), now):
            self.counts.statuses += 1

    # The air ----------------------------------------------------------------------------------
    def _other(self, end: RadioEnd) -> RadioEnd:
        return self.air if end is self.ground else self.ground

    def _window_start(self, now: float, owner: RadioEnd) -> None:
        for end in (self.ground, self.air):
            end.yielded = False
            end.bonus = False
        end_at = now + self.timing.window_s
        self._at(now, lambda t: self._air_turn(t, owner, end_at))

    def _window_over(self, now: float, owner: RadioEnd) -> None:
        self._at(now + self.timing.silence_s, lambda t: self._window_start(t, self._other(owner)))

    def _air_turn(self, now: float, owner: RadioEnd, end_at: float) -> None:
        """The air is free at ``now`` in ``owner``'s window: who sends what."""
        timing = self.timing
        other = self._other(owner)
        sender: RadioEnd | None = None
        if not owner.yielded:
            sender = owner
        elif other.bonus and not other.yielded:
            sender = other
        remaining = end_at - now
        if sender is None or remaining < timing.latency_s:
            self._at(end_at, lambda t: self._window_over(t, owner))
            return
        max_xmit = int((remaining - timing.latency_s) / timing.byte_s)
        if max_xmit < TRAILER_BYTES + 16:
            self._at(end_at, lambda t: self._window_over(t, owner))
            return
        max_xmit = min(max_xmit - (TRAILER_BYTES + 1), timing.max_data)
        pieces = self._take(sender, max_xmit, now)
        kind = "data"
        size = sum(b - a for _, a, b in pieces)
        if not pieces:
            if sender is owner and sender.stats_due:
                kind, size = "stats", STATISTICS_BYTES
                sender.stats_due = False
            else:
                kind = "yield"
                sender.yielded = True
                self.counts.yields += 1
        duration = timing.packet_s(size)
        lost = self._lost(now)
        self.counts.packets += 1
        if kind == "data":
            self.counts.data_air_s += duration
        if lost:
            self.counts.packets_lost += 1
        receiver = self._other(sender)
        self._at(
            now + duration,
            lambda t: self._arrive(t, sender, receiver, kind, pieces, lost, owner),
        )
        # SiK leaves a packet latency after each packet ("receivers don't cope well with back
        # to back packets").
        self._at(now + duration + timing.latency_s, lambda t: self._air_turn(t, owner, end_at))

    def _take(self, end: RadioEnd, max_xmit: int, now: float) -> list[tuple[FramePiece, int, int]]:
        """Whole frames from ``end``'s serial-in buffer up to ``max_xmit`` bytes, or a piece of
        the first frame when it alone is longer (SiK's MAVLink framing)."""
        out: list[tuple[FramePiece, int, int]] = []
        room = max_xmit
        while end.serial_in and room > 0:
            piece = end.serial_in[0]
            left = len(piece.frame) - piece.sent
            if left > room and out:
                break
            n = min(left, room)
            out.append((piece, piece.sent, piece.sent + n))
            piece.sent += n
            room -= n
            end.serial_in_used -= n
            if piece.sent == len(piece.frame):
                end.serial_in.popleft()
                if is_heartbeat(piece.frame) and self.config.status:
                    end.heartbeat_seen = True
                    self._report(end, now)
        return out

    def _lost(self, now: float) -> bool:
        lost = self._channel.lost()
        if self._fades:
            self._fades = [(a, b) for a, b in self._fades if b > now]
            lost = lost or any(a <= now < b for a, b in self._fades)
        return lost

    def _arrive(
        self,
        now: float,
        sender: RadioEnd,
        receiver: RadioEnd,
        kind: str,
        pieces: list[tuple[FramePiece, int, int]],
        lost: bool,
        owner: RadioEnd,
    ) -> None:
        if lost:
            receiver.rx_errors += 1
            for piece, _, _ in pieces:
                piece.broken = True
                if self._complete(piece, pieces):
                    self.counts.broken_frames += 1
            return
        receiver.heard_at = now
        level = RSSI_GOOD + self._jitter.uniform(-6.0, 6.0)
        if self._channel.bad:
            level = RSSI_BAD + self._jitter.uniform(-6.0, 6.0)
        receiver.rssi = (level + 7 * receiver.rssi) / 8
        if kind == "stats":
            receiver.remote_rssi = int(sender.rssi)
            receiver.remote_noise = int(sender.noise)
            return
        if kind == "yield":
            if sender is owner:
                receiver.bonus = True  # the owner gave up the rest of its window
            return
        for piece, _, b in pieces:
            if b != len(piece.frame):
                continue  # more of this frame comes in a later packet
            if piece.broken:
                self.counts.broken_frames += 1
                continue
            if self._to_host(receiver, piece.frame, now):
                if receiver is self.air:
                    self.counts.frames_to_vehicle += 1
                else:
                    self.counts.frames_to_ground += 1
            else:
                self.counts.serial_out_drops += 1

    @staticmethod
    def _complete(piece: FramePiece, pieces: list[tuple[FramePiece, int, int]]) -> bool:
        return any(p is piece and b == len(p.frame) for p, _, b in pieces)

    def _link_update(self, now: float) -> None:
        """tdm.c ``link_update``, every 0.5 s: a radio that heard nothing drifts to the noise,
        forgets the remote figures after 2.5 s, and owes a statistics packet."""
        for end in (self.ground, self.air):
            silent = now - end.heard_at
            if silent > LINK_UPDATE_S:
                end.rssi = (end.noise + 3 * end.rssi) / 4
            if silent > 5 * LINK_UPDATE_S:
                end.remote_rssi = end.remote_noise = 0
            end.noise = (NOISE + self._jitter.uniform(-3.0, 3.0) + 3 * end.noise) / 4
            end.stats_due = True
        self._at(now + LINK_UPDATE_S, self._link_update)
