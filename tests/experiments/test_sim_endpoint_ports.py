"""The loopback ports the demo's vehicle-sim endpoint and its MAVSDK peer are given."""

from __future__ import annotations

from experiments.sim_endpoint import PORT_RANGE, free_udp_ports


def test_the_ports_are_distinct_and_below_the_ephemeral_range():
    """Picked free and released in Linux's ephemeral range (32768-60999), a port could be
    handed to any socket bound to port 0 (another endpoint's, MAVSDK's) before the demo's
    companion bound it: the BIND_ERROR the tests' ports were moved out of that range for."""
    for _ in range(20):
        ports = free_udp_ports(4)
        assert len(set(ports)) == 4
        assert all(PORT_RANGE[0] <= p < PORT_RANGE[1] < 32768 for p in ports)
