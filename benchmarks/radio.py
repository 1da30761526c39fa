"""Mission transfers over an emulated SiK radio pair (sim/radio.py): items x air rate x burst
loss, the project's client against the classic one-request-at-a-time client and against the
air time the items need.

Run: ``python -m benchmarks.radio`` (the full table, about an hour and a half with ``--jobs
4``), ``--quick`` for a small one; ``--target`` for the issue-33 check only (1,000 items at
64 kbit/s with 5 % burst loss, 20 runs); ``--floor`` for issue 51's check (the same 1,000
items, 5 runs of each transfer with the radios' RADIO_STATUS on and off, the mission protocol
against the item count times the round trip measured on the radio in the same run, MAVFTP
against its air time; about 11 minutes with ``--jobs 5``). Each run is a fresh mock vehicle
(ArduPilot) behind a fresh radio pair with its own loss seed; runs go ``--jobs`` at a time in
separate processes (each uses a few per cent of a core: the radio waits on its air time, not on
the CPU).

Columns:

* **air time**: the frames a transfer needs (upload and read-back, no resend, no heartbeat),
  both directions one after the other on the half-duplex channel, in full SiK packets
  (248 data bytes, a 4-byte trailer and a packet latency each) at the air rate;
* **TDM floor**: what the mission protocol itself allows on a TDM radio. The upload is led by
  the vehicle, one request and one item at a time, and on SiK each request and each answer
  waits for its sender's window (a radio that yielded its window cannot send again until its
  next one: tdm.c, ``transmit_yield``): one TDM round per item. The read-back is the air time
  of its frames;
* **FTP air time**: the same for MAVFTP (``@MISSION/mission.dat``: 239-byte WriteFile pieces
  and their ACKs, then the burst read back), MAVLink 2 trimming the payloads' trailing zeros;
  the items up and back, whichever way the upload is then verified;
* **FTP CRC air time**: the frames the default verification sends instead of the read-back:
  the file's first item (the vehicle's home) by one ReadFile in a session of its own, and
  CalcFileCRC32 (``--verify read`` reads the whole file back instead);
* **FTP**: the project's client by MAVFTP against the mock's ArduPilot FTP server, which
  paces a burst to a third of the serial rate as ArduPilot does on a port without flow
  control (GCS_FTP.cpp, BurstReadFile) — the read-back's floor, at 57,600 baud about 7
  packets (1.7 kB) a second;
* **project** / **classic**: medians of wall seconds for upload and verified read-back, and
  how many of the runs verified. "classic" is the specification's plain client: one request at
  a time, a fixed 0.25 s item timeout, no reading of RADIO_STATUS.

A false failure is a run reported failed while the vehicle holds the mission; a false success
one reported verified while it does not.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

from gcs_planner.sim.radio import RadioConfig, SikRadio, Timing
from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from benchmarks.report import machine
from gcs_planner.errors import InputError, LinkError
from gcs_planner.link.connection import mavlink, open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.protocol import ITEM_TIMEOUT_S, item_to_message, mission_differences
from gcs_planner.link.rtt import RoundTrip
from gcs_planner.mission.items import MissionItem

BURST = 4.0  # mean loss burst, packets
TARGET_FACTOR = 2.0  # issue 33: within 2x the air time


def mission(n: int) -> list[MissionItem]:
    return [
        MissionItem(i, 0, 16, x=305_000_000 + 97 * i, y=1_235_000_000 + 89 * i, z=500.0 + i % 7)
        for i in range(n)
    ]


def _frame_bytes(n: int) -> dict[str, int]:
    """Bytes of a loss-free upload and read-back of ``n`` items, by phase and direction, with
    ArduPilot's messages (MISSION_REQUEST on upload; MISSION_REQUEST_INT and MISSION_ITEM_INT
    on read-back)."""
    mav = mavlink.MAVLink(None, 255, 190)

    def size(msg: object) -> int:
        return len(msg.pack(mav))  # type: ignore[attr-defined]

    item = size(item_to_message(mav, mission(2)[1], 1, 1))
    count = size(mav.mission_count_encode(1, 1, n, 0))
    request = size(mav.mission_request_encode(1, 1, n // 2, 0))
    request_int = size(mav.mission_request_int_encode(1, 1, n // 2, 0))
    request_list = size(mav.mission_request_list_encode(1, 1, 0))
    ack = size(mav.mission_ack_encode(1, 1, 0, 0))
    return {
        "upload_ground": count + n * item,
        "upload_vehicle": n * request + ack,
        "back_ground": request_list + n * request_int + ack,
        "back_vehicle": count + n * item,
    }


def _ftp_frame_bytes(n: int, verify: str = "read") -> dict[str, int]:
    """Bytes of a loss-free MAVFTP upload and its verification (``read``: the burst
    read-back; ``crc``: the first item read and the CRC asked) of ``n`` items, by phase and
    direction (MAVLink 2 frames as pymavlink packs them)."""
    from gcs_planner.link import ftp
    from gcs_planner.link.mission_ftp import MISSION_PATH, encode_mission

    mav = mavlink.MAVLink(None, 255, 190)
    data = encode_mission(mission(n))
    pieces = [data[o : o + ftp.DATA_MAX] for o in range(0, len(data), ftp.DATA_MAX)]

    def size(opcode: int, data: bytes = b"", offset: int = 0) -> int:
        payload = ftp.pack(1, 1, opcode, offset, data)
        return len(mav.file_transfer_protocol_encode(0, 1, 1, payload).pack(mav))

    name = MISSION_PATH.encode()
    ack = size(ftp.ACK, offset=len(data))
    control = size(ftp.RESET_SESSIONS) + size(ftp.CREATE_FILE, name) + size(ftp.TERMINATE_SESSION)
    up = {
        "upload_ground": control + sum(size(ftp.WRITE_FILE, p, 9999) for p in pieces),
        "upload_vehicle": (len(pieces) + 3) * ack,
    }
    if verify == "crc":
        first = data[:48]  # the header and item 0
        return {
            **up,
            "back_ground": size(ftp.OPEN_FILE_RO, name) + size(ftp.READ_FILE)
            + size(ftp.TERMINATE_SESSION) + size(ftp.CALC_FILE_CRC32, name),
            "back_vehicle": 3 * ack + size(ftp.ACK, first, 9999) + size(ftp.ACK, b"\xff" * 4),
        }  # fmt: skip
    return {
        **up,
        "back_ground": size(ftp.OPEN_FILE_RO, name) + 2 * size(ftp.BURST_READ_FILE),
        "back_vehicle": 3 * ack + sum(size(ftp.ACK, p, 9999) for p in pieces),
    }


def ftp_air_time(n: int, air_rate: int, verify: str = "read") -> float:
    """Seconds of air the frames of a MAVFTP upload and its verification need (``read``: the
    burst read-back, the items up and back; ``crc``: the CRC and the home item)."""
    t = Timing.of(RadioConfig(air_rate=air_rate))
    return sum(_air(b, t) for b in _ftp_frame_bytes(n, verify).values())


def _air(nbytes: int, t: Timing) -> float:
    """Air time of ``nbytes`` in full SiK packets."""
    packets = math.ceil(nbytes / t.max_data)
    return nbytes * t.byte_s + packets * (t.latency_s + 4 * t.byte_s)


def air_time(n: int, air_rate: int) -> float:
    """Seconds of air the frames of an upload and its read-back need (see the module)."""
    t = Timing.of(RadioConfig(air_rate=air_rate))
    return sum(_air(b, t) for b in _frame_bytes(n).values())


def tdm_floor(n: int, air_rate: int) -> float:
    """The mission protocol's least time on a SiK pair: a TDM round per uploaded item, then
    the read-back's air time."""
    t = Timing.of(RadioConfig(air_rate=air_rate))
    f = _frame_bytes(n)
    return (
        n * 2 * (t.window_s + t.silence_s) + _air(f["back_ground"], t) + _air(f["back_vehicle"], t)
    )


@dataclass(frozen=True)
class Case:
    items: int
    air_rate: int
    loss: float
    client: str  # "project", "classic" or "ftp"
    seed: int
    verify: str = "crc"  # how an FTP upload is verified (the mission protocol reads back)
    status: bool = True  # the radios write RADIO_STATUS to their hosts
    probe: int = 0  # round trips to measure on the radio before the transfer


def round_trip(client: MissionClient, count: int) -> float:
    """The radio's round trip, measured on it: the median of ``count`` exchanges one at a
    time, PARAM_REQUEST_READ answered by PARAM_VALUE (a request and an answer of about a
    mission request's and a mission item's size); an exchange lost is not counted."""
    samples: list[float] = []
    for _ in range(count):
        asked = time.perf_counter()
        client.link.send(client.mav.param_request_read_encode(*client._target(), b"", 0))
        if client._recv(3.0, {"PARAM_VALUE"}, None) is not None:
            samples.append(time.perf_counter() - asked)
    return statistics.median(samples) if samples else math.nan


def _classic(client: MissionClient) -> None:
    """The specification's plain client: one request at a time, 0.25 s item timeout, radio
    reports ignored."""
    client.window = 1
    client._rtt = RoundTrip(ITEM_TIMEOUT_S, ITEM_TIMEOUT_S)
    client._resend_wait = lambda attempts: ITEM_TIMEOUT_S  # type: ignore[method-assign]
    client.radio.observe = lambda msg: msg.get_type() == "RADIO_STATUS"  # type: ignore


def transfer(case: Case) -> dict[str, object]:
    """One verified upload over a fresh radio pair; seconds, and what was reported and held."""
    items = mission(case.items)
    for _ in range(5):  # a port taken by a parallel run between probe and bind: another one
        try:
            port = free_udp_port()
            vehicle = MockVehicle(f"udpin:127.0.0.1:{port}", capacity=max(case.items, 1))
            break
        except InputError:
            continue
    else:
        raise RuntimeError("no free UDP port")
    cfg = RadioConfig(
        air_rate=case.air_rate, loss=case.loss, burst=BURST, seed=case.seed, status=case.status
    )
    with vehicle, SikRadio("udpin:127.0.0.1:0", f"udpout:127.0.0.1:{port}", cfg) as radio:
        link = open_link(radio.ground_connection)
        error = ""
        upload_s = verify_s = 0.0
        verified_by = ""
        try:
            client = MissionClient(
                link, transfer="ftp" if case.client == "ftp" else "mission", verify=case.verify
            )
            if case.client == "classic":
                _classic(client)
            client.connect(timeout=30.0)
            rtt = round_trip(client, case.probe) if case.probe else math.nan
            start = time.perf_counter()
            try:
                report = client.upload_verified(items)
                verified = True
                upload_s, verify_s = report.upload_seconds, report.verify_seconds
                verified_by = report.verify
            except LinkError as exc:
                verified, error = False, str(exc)
            seconds = time.perf_counter() - start
            resends = client.retry_count
        finally:
            link.close()
        holds = not mission_differences(items, vehicle.mission, skip_home=True)
        lost = radio.counts.packets_lost / max(1, radio.counts.packets)
    return {
        "case": case,
        "seconds": seconds,
        "upload_s": upload_s,
        "verify_s": verify_s,
        "verified": verified,
        "verified_by": verified_by,
        "holds": holds,
        "resends": resends,
        "lost": lost,
        "error": error,
        "rtt": rtt,
    }


def run_cases(cases: list[Case], jobs: int) -> list[dict[str, object]]:
    if jobs <= 1:
        return [transfer(c) for c in cases]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(transfer, cases))


def _median(done: list[dict[str, object]], key: str) -> float:
    return statistics.median(float(d[key]) for d in done)  # type: ignore[arg-type]


def render(results: list[dict[str, object]]) -> str:
    groups: dict[tuple[int, int, float], dict[str, list[dict[str, object]]]] = {}
    for r in results:
        c = r["case"]
        assert isinstance(c, Case)
        groups.setdefault((c.items, c.air_rate, c.loss), {}).setdefault(c.client, []).append(r)
    head = [
        "| items | air rate | burst loss | air time | TDM floor | project | verified | "
        "classic | verified | FTP air time | FTP CRC air time | FTP | verified | by CRC | "
        "false fail / success |",
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    rows = []
    for (n, rate, loss), by in sorted(groups.items()):
        air = air_time(n, rate)
        cells = [f"{n:,}", f"{rate} kbit/s", f"{loss:.0%}", f"{air:.1f} s",
                 f"{tdm_floor(n, rate):.1f} s"]  # fmt: skip
        falses = [0, 0]
        for who in ("project", "classic", "ftp"):
            if who == "ftp":
                cells.append(f"{ftp_air_time(n, rate):.1f} s")
                cells.append(f"{ftp_air_time(n, rate, 'crc'):.1f} s")
            done = by.get(who, [])
            if not done:
                cells += ["–", "–"] + (["–"] if who == "ftp" else [])
                continue
            med = _median(done, "seconds")
            ok = sum(bool(d["verified"]) for d in done)
            own = ftp_air_time(n, rate) if who == "ftp" else air
            cells += [f"{med:.1f} s ({med / own:.1f}×)", f"{ok}/{len(done)}"]
            if who == "ftp":
                cells.append(f"{sum(d['verified_by'] == 'crc' for d in done)}/{len(done)}")
            falses[0] += sum(1 for d in done if d["holds"] and not d["verified"])
            falses[1] += sum(1 for d in done if d["verified"] and not d["holds"])
        cells.append(f"{falses[0]} / {falses[1]}")
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(head + rows)


def target_line(results: list[dict[str, object]], who: str = "project") -> str:
    done = [
        r
        for r in results
        if isinstance(r["case"], Case)
        and (r["case"].items, r["case"].air_rate, r["case"].loss, r["case"].client)
        == (1000, 64, 0.05, who)
    ]
    if not done:
        return ""
    air = air_time(1000, 64) if who != "ftp" else ftp_air_time(1000, 64)
    med = _median(done, "seconds")
    worst = max(float(d["seconds"]) for d in done)  # type: ignore[arg-type]
    up = _median(done, "upload_s")
    back = _median(done, "verify_s")
    ff = sum(1 for d in done if d["holds"] and not d["verified"])
    fs = sum(1 for d in done if d["verified"] and not d["holds"])
    met = med <= TARGET_FACTOR * air and ff == 0 and fs == 0
    extra = ""
    by_crc = sum(d["verified_by"] == "crc" for d in done)
    if who == "ftp" and not by_crc:
        extra = " Verified by the full read-back."
    elif who == "ftp":
        own = ftp_air_time(1000, 64, "crc")
        extra = (
            f" Verified by the vehicle's CRC in {by_crc} of {len(done)} runs (the others read "
            f"back); against the {own:.1f} s of air the upload and the CRC's frames need: "
            f"median {med / own:.2f}x, slowest {worst / own:.2f}x."
        )
    return (
        f"Target{' by MAVFTP' if who == 'ftp' else ''} (1,000 items, 64 kbit/s, 5 % burst "
        f"loss, {len(done)} runs): median "
        f"{med:.1f} s (upload {up:.1f} s, verification {back:.1f} s; slowest {worst:.1f} s) "
        f"against {TARGET_FACTOR:g} x {air:.1f} s of air time = {TARGET_FACTOR * air:.1f} s: "
        f"{'met' if met else 'NOT met'}; {ff} false failures, {fs} false successes." + extra
    )


FLOOR_FACTOR = 1.25  # issue 51: the mission protocol within 1.25x its round-trip floor
FTP_FACTOR = 1.5  # issue 51: MAVFTP within 1.5x the air time
PROBES = 20  # round trips measured per run


def floor_cases(runs: int, n: int = 1000, rate: int = 64, loss: float = 0.05) -> list[Case]:
    """Issue 51's Done-when: each transfer with and without RADIO_STATUS, ``runs`` seeds, the
    radio's round trip measured in each run. The long mission-protocol runs go first."""
    return [
        Case(n, rate, loss, who, seed, status=status, probe=PROBES)
        for who in ("project", "ftp")
        for status in (True, False)
        for seed in range(runs)
    ]


def render_floor(results: list[dict[str, object]]) -> str:
    """The Done-when table: medians, each mission-protocol run against its own round-trip
    floor (items x the round trip measured on its radio), each FTP run against the air time
    its frames need (upload and read-back, as the FTP columns of :func:`render`)."""
    head = [
        "| transfer | RADIO_STATUS | runs | verified | median | slowest | round trip "
        "(median) | floor | median / floor | resends (median) | air lost |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    rows, lines = [], []
    groups: dict[tuple[str, bool], list[dict[str, object]]] = {}
    for r in results:
        c = r["case"]
        assert isinstance(c, Case)
        groups.setdefault((c.client, c.status), []).append(r)
    for (who, status), done in sorted(groups.items(), key=lambda g: (g[0][0], not g[0][1])):
        c0 = done[0]["case"]
        assert isinstance(c0, Case)
        n, rate = c0.items, c0.air_rate
        rtt = _median(done, "rtt")
        if who == "ftp":
            floor_s = ftp_air_time(n, rate)
            what, factor, floor_text = "MAVFTP", FTP_FACTOR, f"{floor_s:.1f} s of air"
            ratios = [float(d["seconds"]) / floor_s for d in done]  # type: ignore[arg-type]
        else:
            floor_s = n * rtt
            what, factor, floor_text = "mission protocol", FLOOR_FACTOR, f"{n:,} x {rtt:.3f} s"
            ratios = [
                float(d["seconds"]) / (n * float(d["rtt"]))  # type: ignore[arg-type]
                for d in done
            ]
        ok = sum(bool(d["verified"]) and bool(d["holds"]) for d in done)
        med = _median(done, "seconds")
        worst = max(float(d["seconds"]) for d in done)  # type: ignore[arg-type]
        ratio = statistics.median(ratios)
        rows.append(
            f"| {what} | {'on' if status else 'off'} | {len(done)} | {ok}/{len(done)} | "
            f"{med:.1f} s | {worst:.1f} s | {rtt * 1000:.0f} ms | {floor_text} = "
            f"{floor_s:.1f} s | {ratio:.2f}× | {_median(done, 'resends'):.0f} | "
            f"{_median(done, 'lost'):.1%} |"
        )
        if status:
            met = ratio <= factor and ok == len(done)
            lines.append(
                f"{what} with RADIO_STATUS: median {ratio:.2f}x its "
                f"{'air time' if who == 'ftp' else 'round-trip floor'} against {factor:g}x: "
                f"{'met' if met else 'NOT met'}"
            )
    by = {k: _median(v, "seconds") for k, v in groups.items()}
    if ("ftp", False) in by and ("project", False) in by:
        lines.append(
            f"without RADIO_STATUS: MAVFTP {by[('ftp', False)]:.1f} s against the mission "
            f"protocol's {by[('project', False)]:.1f} s on the same link"
        )
    return "\n".join(head + rows) + "\n\n" + "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(prog="python -m benchmarks.radio")
    p.add_argument("--quick", action="store_true", help="100 and 300 items, 2 runs")
    p.add_argument("--target", action="store_true", help="the 1,000-item target only")
    p.add_argument(
        "--floor",
        action="store_true",
        help="issue 51: 1,000 items at 5 %% burst loss against the measured round-trip floor "
        "and the air time, with and without RADIO_STATUS (default 5 runs each)",
    )
    p.add_argument("--runs", type=int, default=None, help="runs per cell (default 5; 20 target)")
    p.add_argument("--jobs", type=int, default=4, help="runs at once (separate processes)")
    p.add_argument("--classic-runs", type=int, default=None, help="runs of the classic client")
    p.add_argument("--ftp-runs", type=int, default=None, help="runs by MAVFTP (default: --runs)")
    p.add_argument("--no-project", action="store_true", help="skip the mission-protocol runs")
    p.add_argument(
        "--verify",
        choices=("crc", "read"),
        default="crc",
        help="how the FTP runs verify: the vehicle's CRC (default) or the full read-back",
    )
    args = p.parse_args(argv)
    if args.floor:
        cases = floor_cases(args.runs or 5)
        print(f"{len(cases)} transfers, {args.jobs} at a time; {machine()}", file=sys.stderr)
        start = time.perf_counter()
        results = run_cases(cases, args.jobs)
        print(render_floor(results))
        for e in sorted({str(r["error"])[:160] for r in results if r["error"]})[:5]:
            print(f"- failure: {e}")
        print(f"\n({time.perf_counter() - start:.0f} s wall)", file=sys.stderr)
        return
    if args.target:
        runs = args.runs or 20
        cells = [(1000, 64, 0.05)]
    elif args.quick:
        runs = args.runs or 2
        cells = [(n, r, lo) for n in (100, 300) for r in (64, 250) for lo in (0.0, 0.05)]
    else:
        runs = args.runs or 5
        cells = [(n, r, lo) for n in (100, 1000) for r in (64, 250) for lo in (0.0, 0.05)]
    classic_runs = args.classic_runs if args.classic_runs is not None else min(runs, 3)
    ftp_runs = args.ftp_runs if args.ftp_runs is not None else runs
    cases = (
        []
        if args.no_project
        else [Case(n, r, lo, "project", s) for n, r, lo in cells for s in range(runs)]
    )
    cases += [Case(n, r, lo, "classic", s) for n, r, lo in cells for s in range(classic_runs)]
    cases += [Case(n, r, lo, "ftp", s, args.verify) for n, r, lo in cells for s in range(ftp_runs)]
    print(f"{len(cases)} transfers, {args.jobs} at a time; {machine()}", file=sys.stderr)
    start = time.perf_counter()
    results = run_cases(cases, args.jobs)
    print(render(results))
    for who in ("project", "ftp"):
        line = target_line(results, who)
        if line:
            print("\n" + line)
    errors = sorted({str(r["error"])[:160] for r in results if r["error"]})
    for e in errors[:5]:
        print(f"- failure: {e}")
    print(f"\n({time.perf_counter() - start:.0f} s wall)", file=sys.stderr)


if __name__ == "__main__":
    main()
