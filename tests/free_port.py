"""A UDP port on loopback, free now, for a test's MAVLink peer to bind a moment later."""

from __future__ import annotations

from experiments.sim_endpoint import free_udp_ports


def free_udp_port() -> int:
    """A UDP port below Linux's ephemeral range that can be bound on 127.0.0.1 right now
    (experiments.sim_endpoint.free_udp_ports)."""
    return free_udp_ports(1)[0]
