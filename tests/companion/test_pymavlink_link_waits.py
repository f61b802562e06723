"""The pymavlink Link sleeps while it waits for an autopilot, as the control loop does."""

from __future__ import annotations

import socket

import pytest
from pymavlink import mavutil

from companion.link import LinkError
from companion.pymavlink_link import PymavlinkLink


def test_waiting_for_a_heartbeat_sleeps_in_the_socket_instead_of_spinning(monkeypatch):
    """No autopilot on the port: connect gives up after its timeout having asked the socket a
    handful of times (it asked millions of times a second before: a core spent at the
    companion's real-time priority, starving the rest of the companion computer)."""
    calls = []
    recv_match = mavutil.mavfile.recv_match

    def counted(self, *args, **kwargs):
        calls.append(kwargs.get("blocking", False))
        return recv_match(self, *args, **kwargs)

    monkeypatch.setattr(mavutil.mavfile, "recv_match", counted)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    link = PymavlinkLink(f"udpin://127.0.0.1:{port}")
    try:
        with pytest.raises(LinkError, match="no autopilot heartbeat"):
            link.connect(timeout_s=0.6)
    finally:
        link.close()
    assert 0 < sum(calls) < 20, f"{sum(calls)} blocking receives in 0.6 s"
