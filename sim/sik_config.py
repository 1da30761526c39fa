"""The radio pair's configuration: SiK's parameters (``parameters.c``), the TDM timing its
firmware derives from the air rate (``tdm.c``: ``tdm_init``), and the burst-loss channel the
air packets cross (:mod:`sim.radio` describes the whole model).
"""

from __future__ import annotations

import random
from dataclasses import dataclass

TICK_S = 16e-6  # SiK's timer2 tick
MAX_PACKET_LENGTH = 252  # radio.h
TRAILER_BYTES = 4  # tdm.c: struct tdm_trailer (window/flags word and CRC)


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
