"""MAVLink 2 signing between the client and the mock vehicle: right key works, others refused."""

from __future__ import annotations

import pytest

from gcs_planner.errors import LinkError
from gcs_planner.link.connection import open_link
from gcs_planner.link.mission_client import MissionClient
from gcs_planner.link.signing import key_from_passphrase
from gcs_planner.mission.items import MissionItem
from sim.vehicle import MockVehicle, free_udp_port

ITEMS = [MissionItem(i, 0, 16, x=305_000_000 + i, y=1_235_000_000, z=100.0) for i in range(5)]


def _client(port: int, key: bytes | None) -> MissionClient:
    link = open_link(f"udpout:127.0.0.1:{port}", signing_key=key)
    return MissionClient(link, timeout=0.3, retries=1)


def test_key_from_passphrase():
    key = key_from_passphrase("correct horse")
    assert len(key) == 32
    assert key != key_from_passphrase("correct horsf")
    with pytest.raises(ValueError):
        key_from_passphrase("")


def test_right_key_works():
    key = key_from_passphrase("sea-trial")
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=key) as vehicle:
        client = _client(port, key)
        try:
            client.connect(timeout=5.0)
            client.upload_verified(ITEMS)
        finally:
            client.link.close()
        assert vehicle.mission == ITEMS
        assert vehicle.refused_signature == 0


def test_wrong_key_is_refused_by_both_ends():
    port = free_udp_port()
    vehicle_key = key_from_passphrase("sea-trial")
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=vehicle_key) as vehicle:
        client = _client(port, key_from_passphrase("not-the-key"))
        try:
            with pytest.raises(LinkError, match="unsigned or signed with another key"):
                client.connect(timeout=2.5)
        finally:
            client.link.close()
        assert vehicle.refused_signature > 0
        assert vehicle.mission == []


def test_unsigned_vehicle_is_refused_by_a_signing_client():
    port = free_udp_port()
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4"):
        client = _client(port, key_from_passphrase("sea-trial"))
        try:
            with pytest.raises(LinkError, match="unsigned or signed with another key"):
                client.connect(timeout=2.5)
        finally:
            client.link.close()


def test_unsigned_client_is_refused_by_a_signing_vehicle():
    port = free_udp_port()
    key = key_from_passphrase("sea-trial")
    with MockVehicle(f"udpin:127.0.0.1:{port}", flavour="px4", signing_key=key) as vehicle:
        client = _client(port, None)
        try:
            # The unsigned client can hear the vehicle but nothing it sends is accepted.
            client.connect(timeout=5.0)
            with pytest.raises(LinkError, match="no answer"):
                client.upload(ITEMS)
        finally:
            client.link.close()
        assert vehicle.refused_signature > 0
        assert vehicle.mission == []
