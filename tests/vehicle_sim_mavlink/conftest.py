"""Fixtures for the MAVLink endpoint tests: a running endpoint and a pymavlink client."""

from __future__ import annotations

import pytest
from mavlink_test_client import Client, make_endpoint


@pytest.fixture
def endpoint():
    ep = make_endpoint(speed=3.0).start()
    yield ep
    ep.stop()


@pytest.fixture
def client(endpoint):
    c = Client(endpoint.local_port)
    c.hello()
    yield c
    c.close()
