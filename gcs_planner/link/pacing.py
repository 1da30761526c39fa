"""Pacing a transfer to the link: what the local telemetry radio says of its buffer, and how
many requests the link carries at once.

A SiK radio (and others that copy it) writes a RADIO_STATUS to its host each time it passes on
the host's heartbeat: ``txbuf`` is the free share, in percent, of the buffer where what the host
wrote waits for the air (SiK ``Firmware/radio/serial.c``, ``serial_read_space``). ArduPilot reads
it in ``GCS_MAVLINK::handle_radio_status`` (libraries/GCS_MAVLink/GCS_Common.cpp) and does two
things, both copied here in behaviour:

* a gate, ``last_txbuf_is_greater(33)``: parameter and MAVFTP replies are only sent while the
  radio has more than 33 % free, and a report older than 5 s counts as no radio (the gate is
  open);
* a slowdown of everything periodic, ``stream_slowdown_ms``: +60 ms per report under 20 %
  free, +20 ms under 50 %, -40 ms over 95 % (while above 200 ms), -20 ms over 90 %, at most
  2 s; ArduPilot's mission re-request waits 1 s plus this slowdown
  (``MissionItemProtocol::update``).

MAVProxy reads RADIO_STATUS only for display; its mission download keeps at most five requests
out and asks again for an item only 2 s after asking for it (MAVProxy/modules/lib/
mission_item_protocol.py, ``missing_wps_to_request``): a fixed window. Here the window follows
the link instead (:class:`Window`): the items it delivers per second times the median round
trip, the link's bandwidth-delay product, with a quarter more so that it can grow.
"""

from __future__ import annotations

import math
import statistics
import time
from collections import deque
from collections.abc import Callable
from typing import Any

STALE_S = 5.0  # GCS_MAVLINK::last_txbuf_is_greater: an older report is no radio
GATE_TXBUF = 33  # percent free at or below which nothing optional is sent
SLOWDOWN_MAX_S = 2.0
RADIO_REPORTS = ("RADIO_STATUS", "RADIO")


class RadioFlow:
    """The local radio's last RADIO_STATUS and ArduPilot's reading of it."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self.txbuf: int | None = None
        self.rssi = 0
        self.remote_rssi = 0
        self.reports = 0
        self.at = -math.inf
        self.slowdown_s = 0.0

    def observe(self, msg: Any) -> bool:
        """Take ``msg`` if it is a RADIO_STATUS, or the older RADIO of the same fields, as
        ArduPilot's handle_radio_status takes both (True); else leave it (False)."""
        if msg.get_type() not in RADIO_REPORTS:
            return False
        txbuf = int(msg.txbuf)
        self.txbuf = txbuf
        self.rssi = int(msg.rssi)
        self.remote_rssi = int(msg.remrssi)
        self.reports += 1
        self.at = self.clock()
        # ArduPilot's stream_slowdown_ms steps, in seconds.
        s = self.slowdown_s
        if txbuf < 20 and s < SLOWDOWN_MAX_S:
            s += 0.060
        elif txbuf < 50 and s < SLOWDOWN_MAX_S:
            s += 0.020
        elif txbuf > 95 and s > 0.200:
            s -= 0.040
        elif txbuf > 90 and s > 0:
            s = s - 0.020 if s > 0.020 else 0.0
        self.slowdown_s = s
        return True

    def fresh(self) -> bool:
        return self.clock() - self.at <= STALE_S

    @property
    def present(self) -> bool:
        """A radio reports on this link (its last report is fresh)."""
        return self.txbuf is not None and self.fresh()

    def congested(self) -> bool:
        """ArduPilot's gate closed: a fresh report with at most 33 % of the buffer free. What
        is sent now waits behind a full buffer or is dropped by it."""
        return self.present and self.txbuf is not None and self.txbuf <= GATE_TXBUF

    def extra_wait(self) -> float:
        """What to add to a resend wait: ArduPilot's slowdown while a radio reports."""
        return self.slowdown_s if self.present else 0.0


class Window:
    """How many requests to keep outstanding, between ``low`` and ``high``.

    Its estimate is the delivery rate times the median round trip (the link's bandwidth-delay
    product), a quarter more, plus one. A rate measured through a small window only says what
    that window carries, so while every slot is in use (``limited``) the window also grows by
    one per answer, doubling per round trip as TCP's slow start does, until the estimate
    holds it; a lost answer brings it back down to the estimate. ``high`` bounds what can pile
    up in a radio's buffers (32 items of 49 bytes fit SiK's 1,850-byte serial buffer).

    ``rtt(sample)`` takes a round trip measured under Karn's rule, ``delivered(now, limited)``
    an answer; the rate is taken over the last ``span`` answers, so a fade (no answers) leaves
    the window as it was rather than shrinking it to nothing.
    """

    def __init__(self, start: int, low: int = 2, high: int = 32, span: int = 24) -> None:
        self.low = max(1, low)
        self.high = max(self.low, high)
        self.size = min(self.high, max(self.low, start))
        self._arrivals: deque[float] = deque(maxlen=span)
        self._rtts: deque[float] = deque(maxlen=64)

    def rtt(self, seconds: float) -> None:
        if seconds >= 0:
            self._rtts.append(seconds)

    def estimate(self) -> int | None:
        """ceil(1.25 * rate * median round trip) + 1, or None before there are samples."""
        if len(self._arrivals) < 4 or not self._rtts:
            return None
        span = self._arrivals[-1] - self._arrivals[0]
        if span <= 0:
            return None
        rate = (len(self._arrivals) - 1) / span
        # The median round trip, not the shortest: on a TDM radio a request that catches the
        # other radio's yielded window is answered within the window (tens of ms) while most
        # wait a whole round (about 0.24 s at 64 kbit/s); the shortest would size the window
        # for a link that does not exist.
        return math.ceil(1.25 * rate * statistics.median(self._rtts)) + 1

    def delivered(self, now: float, limited: bool = False) -> None:
        self._arrivals.append(now)
        target = self.estimate()
        grown = self.size + 1 if limited else 0
        if target is None:
            self.size = min(self.high, max(self.size, grown))
            return
        self.size = min(self.high, max(self.low, target, grown, self.size if not limited else 0))

    def lost(self) -> None:
        """An answer was lost: back to the estimate (never below ``low``)."""
        target = self.estimate()
        if target is not None:
            self.size = max(self.low, min(self.size, target))


class Backoff:
    """How many requests a link that says nothing of its buffers (no RADIO_STATUS) is trusted
    with: TCP's congestion avoidance (RFC 5681, 3.1) on a window of requests. One more per
    window of clean answers (about one per round trip), halved at a resend, once per round
    trip (a burst that takes several requests is one loss event: RFC 6582).

    Without a radio's report a resend is the only sign that the link is full: a half-duplex
    link turns a window of requests into a queue that delays every answer, and a resend sent
    into that queue only lengthens it. Halving lets the queue drain; the window then grows
    back at the pace at which answers come.
    """

    def __init__(self, start: int, low: int = 1, high: int = 32) -> None:
        self.low = max(1, low)
        self.high = max(self.low, high)
        self.size = float(min(self.high, max(self.low, start)))
        self.cut_at = -math.inf
        self.halvings = 0

    @property
    def slots(self) -> int:
        """Requests that may be outstanding now."""
        return max(self.low, int(self.size))

    def answered(self) -> None:
        """A clean answer (to a request sent once): additive increase."""
        self.size = min(float(self.high), self.size + 1.0 / self.size)

    def resent(self, now: float, round_trip: float) -> None:
        """A request is sent again at ``now``: halve, unless already halved within the last
        ``round_trip`` (the same loss event)."""
        if now - self.cut_at < round_trip:
            return
        self.size = max(float(self.low), self.size / 2.0)
        self.cut_at = now
        self.halvings += 1
