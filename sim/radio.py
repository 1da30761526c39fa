"""A SiK-class telemetry radio pair between a ground station and the mock vehicle, as a UDP relay.

Both sides connect to the relay over UDP on 127.0.0.1 as they would plug into a radio's serial
port: the ground station to the ground radio, the vehicle to the air radio. Between them the
relay models what the SiK firmware (github.com/ArduPilot/SiK, ``Firmware/radio/``) does with the
bytes, with SiK's default parameters (``parameters.c``: SERIAL_SPEED 57 = 57,600 baud,
AIR_SPEED 64 kbit/s, ECC off, MAVLINK framing on, MAX_WINDOW 131 ms):

* **The serial side.** Each radio's host writes at the serial rate (10 bits a byte); what it
  writes waits for the air in the radio's serial-in buffer (``serial.c``: ``rx_buf``, 1,850
  bytes on the Si1000), and a frame that arrives at a full buffer is dropped (SiK drops the byte
  and counts ``serial_rx_overflow``). What comes off the air waits in the serial-out buffer
  (``tx_buf``, 645 bytes) while the serial line clocks it out to the host; what does not fit is
  dropped (``serial_write_buf`` discards the bytes: "we can't afford to wait"). Drops are whole
  frames here, since a frame with bytes missing fails its CRC at the host anyway.
* **TDM, half duplex** (``tdm.c``). One air channel, two radios taking turns: a transmit window
  each, a silence between. Timing as ``tdm_init`` derives it from the air rate: ticks of 16 us
  per byte ``(8 + 8e6/rate)/16 + 1``, a packet latency of 13 bytes plus 13 ticks, silences of
  two latencies, windows of three full packets (248 data bytes and a 4-byte trailer, 252 at
  most) capped at MAX_WINDOW. In its window a radio sends packets of whole MAVLink frames (a
  frame longer than the packet goes in pieces); after each packet it waits one latency. A
  radio with nothing to send yields: a zero-length packet, after which it cannot send until the
  next window, while the other radio, having heard the yield, may use the rest of the window
  (SiK's ``transmit_yield`` and ``bonus_transmit``). An idle radio sends a statistics packet
  every 0.5 s instead of yielding once (its rssi and noise, the other's "remote" figures).
* **Burst loss.** Each air packet is lost or not by a seeded two-state Gilbert-Elliott channel:
  a good state that loses nothing and a bad state that loses every packet, with the stationary
  share of the bad state equal to the mean loss and a mean stay of ``burst`` packets in it.
  :meth:`SikRadio.fade` adds a fade: every packet lost for a given time.
* **RADIO_STATUS** (``mavlink.c``: ``MAVLink_report``). When a radio passes a heartbeat from its
  host on to the air (``packet.c``: ``check_heartbeat``), it writes a RADIO_STATUS from system
  51 ('3'), component 68 ('D') to its own host, if its serial-out buffer has room: ``txbuf`` the
  free share of its serial-in buffer in percent, in 8-byte steps (``serial_read_space``), rssi
  and noise averaged as ``tdm.c`` averages them (7/8 on each packet received; on a link with no
  packets for 0.5 s, towards the noise), the other radio's figures from its last statistics
  packet, reset after 2.5 s without packets, and ``rxerrors`` the packets lost.

What this does not model: frequency hopping and its search for sync after a long fade (the
radios here stay in step), ECC's error correction (ECC only doubles the air time), opportunistic
resend, RTS/CTS, and the host's own serial buffer, which is taken as large (a writer to a serial
port blocks rather than loses bytes).

Run as a relay process: ``python -m sim.radio --ground udpin:127.0.0.1:14550 --vehicle
udpout:127.0.0.1:14551 [--air-rate 64] [--loss 0.05 --burst 4] [--seed 0]``; or from
``gcs-planner mock-vehicle --radio sik[:AIR_RATE]``.
"""

from __future__ import annotations

import argparse
import heapq
import itertools
import random
import select
import socket
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from gcs_planner.link.connection import mavlink

# SiK's MAVLink report comes from system '3', component 'D' (mavlink.c: RADIO_SOURCE_SYSTEM).
RADIO_SYSTEM = 51
RADIO_COMPONENT = 68
TICK_S = 16e-6  # SiK's timer2 tick
MAX_PACKET_LENGTH = 252  # radio.h
TRAILER_BYTES = 4  # tdm.c: struct tdm_trailer (window/flags word and CRC)
STATISTICS_BYTES = 4  # tdm.c: struct statistics (average rssi and noise, receive count)
LINK_UPDATE_S = 0.5  # tdm.c: link_update every 32,768 ticks
# RSSI in SiK's units (about 1.9 per dBm plus an offset: ardupilot_wiki, "SiK Radio - Advanced
# Configuration"): a good link near 180, the noise floor near 40.
RSSI_GOOD = 180
RSSI_BAD = 70
NOISE = 40


@dataclass(frozen=True)
class RadioConfig:
    """The radio pair's settings (SiK's defaults) and the channel's loss."""

    air_rate: int = 64  # kbit/s, SiK's AIR_SPEED
    serial_baud: int = 57_600
    serial_in_bytes: int = 1850  # serial.c RX_BUFF_MAX (Si1000): host -> air
    serial_out_bytes: int = 645  # serial.c TX_BUFF_MAX (Si1000): air -> host
    max_window_ms: int = 131  # MAX_WINDOW
    ecc: bool = False
    loss: float = 0.0  # mean share of air packets lost
    burst: float = 4.0  # mean length of a loss burst, packets
    seed: int = 0
    status: bool = True  # RADIO_STATUS to each host

    def __post_init__(self) -> None:
        if not 2 <= self.air_rate <= 256:
            raise ValueError(f"air rate {self.air_rate} kbit/s is not in 2..256 (SiK AIR_SPEED)")
        if self.serial_baud < 1200:
            raise ValueError("serial rate below 1,200 baud")
        if not 0.0 <= self.loss < 1.0:
            raise ValueError(f"loss {self.loss!r} is not in [0, 1)")
        if self.burst < 1.0:
            raise ValueError("a loss burst lasts at least one packet")
        if self.serial_in_bytes < 300 or self.serial_out_bytes < 300:
            raise ValueError("radio buffers must hold a largest MAVLink frame (280 bytes)")


@dataclass(frozen=True)
class Timing:
    """SiK's TDM timing for an air rate (``tdm_init``), in seconds and bytes."""

    byte_s: float
    latency_s: float
    silence_s: float
    window_s: float
    max_data: int

    @classmethod
    def of(cls, cfg: RadioConfig) -> Timing:
        ticks_per_byte = (8 + 8_000_000 // (cfg.air_rate * 1000)) // 16 + 1
        latency = (8 + 10 // 2) * ticks_per_byte + 13
        if cfg.ecc:
            max_data = MAX_PACKET_LENGTH // 2 - (6 + TRAILER_BYTES)
            ticks_per_byte *= 2  # golay doubles each byte and adds 4
            latency += 4 * ticks_per_byte
        else:
            max_data = MAX_PACKET_LENGTH - TRAILER_BYTES
        silence = 2 * latency
        window = 3 * (latency + max_data * ticks_per_byte)
        window = min(window, cfg.max_window_ms * (1000 // 16), 0x1FFF)
        return cls(
            byte_s=ticks_per_byte * TICK_S,
            latency_s=latency * TICK_S,
            silence_s=silence * TICK_S,
            window_s=window * TICK_S,
            max_data=max_data,
        )

    def packet_s(self, data_bytes: int) -> float:
        """Air time of one packet carrying ``data_bytes`` (its trailer included)."""
        return self.latency_s + (data_bytes + TRAILER_BYTES) * self.byte_s


class GilbertElliott:
    """Two-state burst loss, one step per air packet: good loses nothing, bad loses all.

    With mean loss ``loss`` and mean burst ``burst`` packets: leave bad with probability
    1/burst, enter it with the probability that makes its stationary share ``loss``.
    """

    def __init__(self, loss: float, burst: float, seed: int) -> None:
        self.rng = random.Random(seed)
        self.leave_bad = 1.0 / burst
        self.enter_bad = self.leave_bad * loss / (1.0 - loss) if loss > 0 else 0.0
        self.bad = False

    def lost(self) -> bool:
        if self.bad:
            self.bad = self.rng.random() >= self.leave_bad
        else:
            self.bad = self.rng.random() < self.enter_bad
        return self.bad


@dataclass
class RadioCounts:
    """What the pair did, for tests and the benchmark."""

    packets: int = 0
    packets_lost: int = 0
    yields: int = 0
    frames_to_vehicle: int = 0
    frames_to_ground: int = 0
    serial_in_drops: int = 0  # frames a full serial-in buffer refused
    serial_out_drops: int = 0  # frames a full serial-out buffer refused
    broken_frames: int = 0  # frames that lost a piece in the air
    statuses: int = 0  # RADIO_STATUS written to the hosts
    data_air_s: float = 0.0  # air time of packets that carried data


class _Piece:
    """A frame in a serial-in buffer: how much of it has gone to the air, and whether a packet
    carrying part of it was lost."""

    __slots__ = ("frame", "sent", "broken")

    def __init__(self, frame: bytes) -> None:
        self.frame = frame
        self.sent = 0
        self.broken = False


@dataclass
class _End:
    """One radio and its host: the serial line in, the buffers, the serial line out."""

    name: str
    sock: socket.socket
    peer: Any  # the host's UDP address (None until heard, for a listening end)
    listening: bool
    line_in_free: float = 0.0
    serial_in: deque[_Piece] = field(default_factory=deque)
    serial_in_used: int = 0
    serial_out: deque[bytes] = field(default_factory=deque)
    serial_out_used: int = 0
    line_out_busy: bool = False
    yielded: bool = False
    bonus: bool = False
    stats_due: bool = True
    rssi: float = 0.0
    noise: float = float(NOISE)
    remote_rssi: int = 0
    remote_noise: int = 0
    rx_errors: int = 0
    heard_at: float = -1e9  # when this radio last received a packet
    heartbeat_seen: bool = False


def _is_heartbeat(frame: bytes) -> bool:
    """SiK's ``check_heartbeat``: a MAVLink 1 or 2 frame whose message id is 0."""
    if len(frame) >= 10 and frame[0] == 0xFD:
        return frame[7] == 0 and frame[8] == 0 and frame[9] == 0
    return len(frame) >= 6 and frame[0] == 0xFE and frame[5] == 0


def _endpoint(text: str) -> tuple[socket.socket, Any, bool]:
    """A UDP socket for ``udpin:HOST:PORT`` (bound there; answers the last sender) or
    ``udpout:HOST:PORT`` (sends there from a free port)."""
    scheme, _, rest = text.partition(":")
    host, _, port_text = rest.rpartition(":")
    if scheme not in ("udpin", "udpout") or not host or not port_text.isdigit():
        raise ValueError(f"{text!r}: the radio relay takes udpin:HOST:PORT or udpout:HOST:PORT")
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setblocking(False)
    if scheme == "udpin":
        sock.bind((host, int(port_text)))
        return sock, None, True
    sock.bind(("127.0.0.1" if host in ("127.0.0.1", "localhost") else "0.0.0.0", 0))
    return sock, (host, int(port_text)), False


class SikRadio:
    """The radio pair as a relay: ``ground`` is where the ground station connects, ``vehicle``
    where the vehicle is (see :func:`_endpoint` for the forms). Runs in a thread:
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
        gsock, gpeer, glisten = _endpoint(ground)
        try:
            vsock, vpeer, vlisten = _endpoint(vehicle)
        except BaseException:
            gsock.close()
            raise
        self.ground = _End("ground", gsock, gpeer, glisten)
        self.air = _End("air", vsock, vpeer, vlisten)
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

    def _drain_socket(self, end: _End) -> None:
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

    def _from_host(self, end: _End, frame: bytes, now: float) -> None:
        # The host's bytes queue on its serial line and reach the radio at the serial rate.
        start = max(now, end.line_in_free)
        done = start + self._serial_s(len(frame))
        end.line_in_free = done
        self._at(done, lambda t: self._into_radio(end, frame))

    def _into_radio(self, end: _End, frame: bytes) -> None:
        if end.serial_in_used + len(frame) > self.config.serial_in_bytes:
            self.counts.serial_in_drops += 1
            return
        end.serial_in.append(_Piece(frame))
        end.serial_in_used += len(frame)

    def _to_host(self, end: _End, frame: bytes, now: float) -> bool:
        """Queue ``frame`` in ``end``'s serial-out buffer; False when it does not fit."""
        if end.serial_out_used + len(frame) > self.config.serial_out_bytes:
            return False
        end.serial_out.append(frame)
        end.serial_out_used += len(frame)
        if not end.line_out_busy:
            end.line_out_busy = True
            self._at(now + self._serial_s(len(frame)), lambda t: self._line_out_done(end, t))
        return True

    def _line_out_done(self, end: _End, now: float) -> None:
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

    def _txbuf(self, end: _End) -> int:
        size = self.config.serial_in_bytes
        free = size - end.serial_in_used
        return (100 * (free // 8)) // (size // 8)

    def _report(self, end: _End, now: float) -> None:
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
    def _other(self, end: _End) -> _End:
        return self.air if end is self.ground else self.ground

    def _window_start(self, now: float, owner: _End) -> None:
        for end in (self.ground, self.air):
            end.yielded = False
            end.bonus = False
        end_at = now + self.timing.window_s
        self._at(now, lambda t: self._air_turn(t, owner, end_at))

    def _window_over(self, now: float, owner: _End) -> None:
        self._at(now + self.timing.silence_s, lambda t: self._window_start(t, self._other(owner)))

    def _air_turn(self, now: float, owner: _End, end_at: float) -> None:
        """The air is free at ``now`` in ``owner``'s window: who sends what."""
        timing = self.timing
        other = self._other(owner)
        sender: _End | None = None
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

    def _take(self, end: _End, max_xmit: int, now: float) -> list[tuple[_Piece, int, int]]:
        """Whole frames from ``end``'s serial-in buffer up to ``max_xmit`` bytes, or a piece of
        the first frame when it alone is longer (SiK's MAVLink framing)."""
        out: list[tuple[_Piece, int, int]] = []
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
                if _is_heartbeat(piece.frame) and self.config.status:
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
        sender: _End,
        receiver: _End,
        kind: str,
        pieces: list[tuple[_Piece, int, int]],
        lost: bool,
        owner: _End,
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
    def _complete(piece: _Piece, pieces: list[tuple[_Piece, int, int]]) -> bool:
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


def parse_radio(text: str) -> int:
    """The air rate of ``sik`` or ``sik:AIR_RATE`` (kbit/s), for ``--radio``."""
    kind, _, rate = text.partition(":")
    if kind.lower() != "sik":
        raise ValueError(f"{text!r}: the radio is sik or sik:AIR_RATE (kbit/s, e.g. sik:64)")
    if not rate:
        return RadioConfig.air_rate
    try:
        value = int(rate)
    except ValueError:
        raise ValueError(f"{text!r}: the air rate is a whole number of kbit/s") from None
    RadioConfig(air_rate=value)  # range-checked there
    return value


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m sim.radio",
        description="A SiK telemetry radio pair between a ground station and a vehicle, as a "
        "UDP relay on this machine.",
    )
    p.add_argument("--ground", default="udpin:127.0.0.1:14550", help="where the GCS connects")
    p.add_argument("--vehicle", required=True, help="the vehicle: udpout:HOST:PORT or udpin:")
    p.add_argument("--air-rate", type=int, default=64, help="kbit/s (SiK AIR_SPEED, default 64)")
    p.add_argument("--baud", type=int, default=57_600, help="serial rate (default 57600)")
    p.add_argument("--loss", type=float, default=0.0, help="mean air packet loss in [0, 1)")
    p.add_argument("--burst", type=float, default=4.0, help="mean loss burst, packets")
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    try:
        cfg = RadioConfig(
            air_rate=args.air_rate,
            serial_baud=args.baud,
            loss=args.loss,
            burst=args.burst,
            seed=args.seed,
        )
        radio = SikRadio(args.ground, args.vehicle, cfg)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    t = radio.timing
    print(
        f"SiK radio at {cfg.air_rate} kbit/s (windows {t.window_s * 1000:.1f} ms, silences "
        f"{t.silence_s * 1000:.1f} ms), serial {cfg.serial_baud} baud; ground "
        f"{args.ground}, vehicle {args.vehicle}; Ctrl-C to stop",
        file=sys.stderr,
    )
    try:
        radio.serve_forever()
    finally:
        radio.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
