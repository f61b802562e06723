"""MavlinkEndpoint lifecycle and configuration: ports, errors, pacing, heartbeats."""

from __future__ import annotations

import socket

import pytest
from mavlink_test_client import Client, make_endpoint, wait_until

from vehicle_sim import Simulator, load_sim_config
from vehicle_sim.mavlink import EndpointConfig, LinkConfig, MavlinkEndpoint, px4_sitl_links


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"speed": 0.0}, "speed must be finite and > 0"),
        ({"speed": float("nan")}, "speed must be finite and > 0"),
        ({"links": ()}, "at least one link"),
        ({"links": (LinkConfig("a"), LinkConfig("a"))}, "link names must be unique"),
    ],
)
def test_bad_endpoint_config_raises(kwargs, message):
    with pytest.raises(ValueError, match=message):
        EndpointConfig(**kwargs)


def test_bad_link_config_raises():
    with pytest.raises(ValueError, match="bind_port must be 0..65535"):
        LinkConfig("x", bind_port=70000)
    with pytest.raises(ValueError, match="signing key must be 32 bytes"):
        LinkConfig("x", signing_key=b"short")


def test_taken_port_raises_naming_the_link():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        links = (LinkConfig("first"), LinkConfig("second", bind_port=port))
        endpoint = MavlinkEndpoint(Simulator(load_sim_config("iris")), EndpointConfig(links=links))
        with pytest.raises(OSError, match=f"cannot bind link second to 127.0.0.1:{port}"):
            endpoint.start()


def test_two_links_each_serve_clients_and_stop_cleanly():
    sim = Simulator(load_sim_config("iris"))
    # Nobody listens on remote ports 1 and 2: the ICMP errors must not disturb the endpoint.
    endpoint = MavlinkEndpoint(sim, EndpointConfig(links=px4_sitl_links(1, 2), speed=2.0))
    with endpoint:
        ports = endpoint.local_ports
        assert set(ports) == {"offboard", "gcs"} and endpoint.local_port == ports["offboard"]
        clients = [Client(ports["offboard"]), Client(ports["gcs"], source_system=200)]
        try:
            for client in clients:
                client.hello()
            assert clients[0].command(400, 1).result == 0
            # a STATUSTEXT from the simulator reaches the client on the other link too
            assert clients[1].recv("STATUSTEXT", 3.0, lambda m: m.text == "Armed") is not None
        finally:
            for client in clients:
                client.close()
        assert endpoint.running
    assert not endpoint.running
    with pytest.raises(RuntimeError, match="already started"):
        endpoint.start()


def test_heartbeats_at_one_hz_wall_clock_even_when_slower_than_real_time():
    endpoint = make_endpoint(speed=0.1).start()
    client = Client(endpoint.local_port)
    try:
        client.hello()
        beats = [client.recv("HEARTBEAT", 3.0) for _ in range(2)]
        assert all(b is not None for b in beats), "a 3 s wall-clock gap between heartbeats"
        assert endpoint.state.t_s < 1.0  # ... although less than a simulated second passed
    finally:
        client.close()
        endpoint.stop()


def test_simulated_time_follows_the_speed_factor(endpoint):
    t0 = endpoint.state.t_s
    wait_until(lambda: endpoint.state.t_s > t0 + 1.5, 5.0, "1.5 s of simulated time")
