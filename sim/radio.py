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

Run as a relay process: ``python -m gcs_planner.sim.radio --ground udpin:127.0.0.1:14550 --vehicle
udpout:127.0.0.1:14551 [--air-rate 64] [--loss 0.05 --burst 4] [--seed 0]``; or from
``gcs-planner mock-vehicle --radio sik[:AIR_RATE]``.
"""

from __future__ import annotations

import argparse
import sys

from gcs_planner.sim.sik_config import (
    MAX_PACKET_LENGTH,
    TICK_S,
    TRAILER_BYTES,
    GilbertElliott,
    RadioConfig,
    Timing,
    parse_radio,
)
from gcs_planner.sim.sik_relay import (
    LINK_UPDATE_S,
    RADIO_COMPONENT,
    RADIO_SYSTEM,
    STATISTICS_BYTES,
    SikRadio,
)
from gcs_planner.sim.sik_serial import NOISE, RSSI_BAD, RSSI_GOOD, RadioCounts

# The radio's parts live by purpose (sik_config: settings, timing and channel; sik_serial: one
# radio and its host; sik_relay: the pair as a relay); their names stay importable from here.
__all__ = [
    "LINK_UPDATE_S",
    "MAX_PACKET_LENGTH",
    "NOISE",
    "RADIO_COMPONENT",
    "RADIO_SYSTEM",
    "RSSI_BAD",
    "RSSI_GOOD",
    "STATISTICS_BYTES",
    "TICK_S",
    "TRAILER_BYTES",
    "GilbertElliott",
    "RadioConfig",
    "RadioCounts",
    "SikRadio",
    "Timing",
    "main",
    "parse_radio",
]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m gcs_planner.sim.radio",
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
