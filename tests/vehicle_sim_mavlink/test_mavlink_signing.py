"""MAVLink 2 signing on a link: unsigned or wrongly signed commands refused and counted."""

from __future__ import annotations

import hashlib

import pytest
from mavlink_test_client import MAV_RESULT_ACCEPTED, Client, make_endpoint, wait_until

KEY = hashlib.sha256(b"correct horse battery staple").digest()


@pytest.fixture
def signed_endpoint():
    ep = make_endpoint(speed=3.0, signing_key=KEY).start()
    yield ep
    ep.stop()


def test_unsigned_commands_are_refused_and_counted(signed_endpoint):
    client = Client(signed_endpoint.local_port)
    try:
        hb = client.hello()  # unsigned HEARTBEATs are allowed, as PX4 does
        assert hb._signed is False  # the unsigned client cannot check the signature ...
        assert hb.get_header().incompat_flags & 1  # ... but the endpoint signed it
        assert client.command(400, 1, timeout_s=1.0) is None
        client.mav.param_request_list_send(1, 1)
        assert client.recv("PARAM_VALUE", 1.0) is None
        assert not signed_endpoint.state.armed
        assert signed_endpoint.stats.signing_rejected == 2
    finally:
        client.close()


def test_wrongly_signed_commands_are_refused(signed_endpoint):
    client = Client(signed_endpoint.local_port, signing_key=hashlib.sha256(b"wrong").digest())
    try:
        assert client.command(400, 1, timeout_s=1.0) is None
        wait_until(lambda: signed_endpoint.stats.signing_rejected >= 1, 2.0, "rejection counted")
        assert not signed_endpoint.state.armed
    finally:
        client.close()


def test_signed_commands_work(signed_endpoint):
    client = Client(signed_endpoint.local_port, signing_key=KEY)
    try:
        hb = client.hello()
        assert hb._signed
        assert client.command(400, 1).result == MAV_RESULT_ACCEPTED
        wait_until(lambda: signed_endpoint.state.armed, 2.0, "armed")
        assert client.set_param("MIS_TAKEOFF_ALT", 3.0).param_value == 3.0
        assert signed_endpoint.stats.signing_rejected == 0
    finally:
        client.close()
