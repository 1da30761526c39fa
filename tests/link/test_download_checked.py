"""A mission downloaded by MAVFTP is checked end to end: by the vehicle's CalcFileCRC32 of its
file, or, where the vehicle offers no CRC, by reading it again by the mission protocol. One
byte altered on the way (a relay that rewrites a frame writes a good frame checksum) exits 4
and writes nothing; before, it gave exit 0 and a latitude 730 m off."""

from __future__ import annotations

import json
from pathlib import Path

from gcs_planner.sim.vehicle import MockVehicle, free_udp_port

from gcs_planner.cli import main
from gcs_planner.link import ftp
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.mission_ftp import (
    CRC_READ,
    HEADER,
    ITEM,
    MAGIC,
    crc32,
    file_crcs,
    read_whole,
    stored_item_bytes,
    xyz_written,
)
from gcs_planner.mission.items import MissionItem

HOME = MissionItem(0, 0, 16, x=305_000_000, y=1_235_000_000, z=5.0)


def _mission(n: int) -> list[MissionItem]:
    return [HOME] + [
        MissionItem(i, 3, 16, x=305_000_000 + 97 * i, y=1_235_000_000 + 89 * i, z=120.0)
        for i in range(1, n)
    ]


def _alter_one_byte(vehicle: MockVehicle) -> list[int]:
    """Flip bit 0 of byte 2 of item 1's latitude in the first burst-read reply only (65,536
    degE7, about 730 m), as a relay that rewrites the frame would."""
    send = vehicle.ftp._send_payload
    flipped: list[int] = []

    def tampered(peer, payload):
        p = ftp.unpack(payload)
        if p.req_opcode == ftp.BURST_READ_FILE and p.opcode == ftp.ACK and not flipped:
            at = 12 + 10 + ITEM.size + 16 + 2 - p.offset  # header, item 0, then item 1's x
            if 12 <= at < 12 + p.size:
                payload = list(payload)
                payload[at] ^= 0x01
                flipped.append(p.offset)
        send(peer, payload)

    vehicle.ftp._send_payload = tampered  # type: ignore[method-assign]
    return flipped


def _no_crc(vehicle: MockVehicle) -> None:
    """An ArduPilot without CalcFileCRC32: answered NAK UnknownCommand."""
    handle = vehicle.ftp.handle

    def without(msg, peer):
        p = ftp.unpack(msg.payload)
        if p.opcode == ftp.CALC_FILE_CRC32:
            vehicle.ftp._nak(peer, p, ftp.UNKNOWN_COMMAND)
            return
        handle(msg, peer)

    vehicle.ftp.handle = without  # type: ignore[method-assign]


def _download(port: int, out: Path) -> int:
    conn = ["--connect", f"udpout:127.0.0.1:{port}", "--quiet", "--timeout", "0.5"]
    return main(["download", *conn, "--out", str(out)])


def test_one_altered_byte_in_an_ftp_download_exits_4_and_writes_nothing(tmp_path, capsys):
    port = free_udp_port()
    out = tmp_path / "m.json"
    with MockVehicle(f"udpin:127.0.0.1:{port}") as vehicle:
        vehicle.missions.commit(_mission(20))
        flipped = _alter_one_byte(vehicle)
        code = _download(port, out)
    err = capsys.readouterr().err.strip()
    assert flipped and code == 4 and not out.exists()
    assert "CRC-32" in err and "altered" in err and "\n" not in err, err


def test_the_crc_passes_an_unaltered_download_and_one_whose_current_item_moved(tmp_path):
    items = _mission(30)
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}") as vehicle:
        vehicle.missions.commit(items)
        handle = vehicle.ftp.handle

        def flying(msg, peer):  # the nav command moves on between the read and the CRC
            if ftp.unpack(msg.payload).opcode == ftp.CALC_FILE_CRC32:
                vehicle.missions.current_seq = 16
            handle(msg, peer)

        vehicle.ftp.handle = flying  # type: ignore[method-assign]
        link = open_link(f"udpout:127.0.0.1:{port}")
        try:
            client = MissionClient(link)
            client.connect(timeout=10.0)
            got = client.download()
        finally:
            link.close()
        assert client.transfer_used == "ftp" and vehicle.ftp.crcs_served == 1
    assert [(g.x, g.y) for g in got[1:]] == [(it.x, it.y) for it in items[1:]]


def test_without_a_crc_the_ftp_download_is_read_again_by_the_mission_protocol(tmp_path):
    items = _mission(20)
    port = free_udp_port()
    out = tmp_path / "m.json"
    with MockVehicle(f"udpin:127.0.0.1:{port}") as vehicle:
        vehicle.missions.commit(items)
        _no_crc(vehicle)
        assert _download(port, out) == 0
    rows = json.loads(out.read_text())["items"]
    assert [(r["x"], r["y"]) for r in rows[1:]] == [(it.x, it.y) for it in items[1:]]
    out.unlink()
    with MockVehicle(f"udpin:127.0.0.1:{port}") as vehicle:
        vehicle.missions.commit(items)
        _no_crc(vehicle)
        flipped = _alter_one_byte(vehicle)
        assert _download(port, out) == 4 and flipped and not out.exists()


def _served(items: list[MissionItem], nav: int | None, chunk: int) -> bytes:
    """mission.dat of ``items`` read in ``chunk``-byte calls while nav command ``nav`` runs."""
    header = HEADER.pack(MAGIC, 0, 0, 0, len(items))
    rendered = [(stored_item_bytes(it, k, nav), "xyz" if k == 0 else xyz_written(it.command))
                for k, it in enumerate(items)]  # fmt: skip
    return read_whole(header, rendered, chunk)


def test_file_crcs_are_the_vehicles_crc_of_the_file_read():
    # No position: what a read call's buffer held is there, and a 64-byte call starts inside it.
    speed = MissionItem(1, 0, 178, param2=22.0)
    items = [HOME, speed, *[it.with_seq(k + 2) for k, it in enumerate(_mission(12))]]
    burst = _served(items, None, 239)
    assert burst != _served(items, None, CRC_READ)  # the leftovers differ with the call size
    assert file_crcs(burst)[0] == crc32(_served(items, None, CRC_READ))
    # A flight moved the nav command between the read and the CRC.
    assert crc32(_served(items, 16, CRC_READ)) in file_crcs(burst)
    altered = bytearray(burst)
    altered[10 + 2 * ITEM.size + 18] ^= 0x01  # item 2's latitude
    assert file_crcs(bytes(altered))[0] != file_crcs(burst)[0]
    assert crc32(_served(items, None, CRC_READ)) not in file_crcs(bytes(altered))
