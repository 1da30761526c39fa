"""How long to wait for an answer before asking again: an estimate of the link's round trip.

A fixed 250 ms per item is right for a radio and 100 times too slow for a link that answers in
2 ms, where every lost frame then costs far more than the transfer itself. Like TCP (RFC 6298),
the resend timeout is the smoothed round trip plus four deviations, measured only on answers to
requests sent once (Karn's rule: an answer to a resent request could belong to either copy), and
kept between a floor and the protocol's item timeout.
"""

from __future__ import annotations


class RoundTrip:
    """Smoothed round-trip time and the resend timeout it gives."""

    def __init__(self, floor: float, ceiling: float) -> None:
        self.floor = min(floor, ceiling)
        self.ceiling = ceiling
        self.srtt: float | None = None
        self.rttvar = 0.0

    def sample(self, seconds: float) -> None:
        if seconds < 0:
            return
        if self.srtt is None:
            self.srtt, self.rttvar = seconds, seconds / 2
        else:
            self.rttvar = 0.75 * self.rttvar + 0.25 * abs(self.srtt - seconds)
            self.srtt = 0.875 * self.srtt + 0.125 * seconds
        self.rttvar = max(self.rttvar, 0.002)

    @property
    def timeout(self) -> float:
        if self.srtt is None:
            return self.ceiling
        return min(self.ceiling, max(self.floor, self.srtt + 4 * self.rttvar))
