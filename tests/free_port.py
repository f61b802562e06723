"""A UDP port on loopback, free now, for a test's MAVLink peer to bind a moment later."""

from __future__ import annotations

import random
import socket

# Below Linux's ephemeral range (32768-60999), from which the simulator endpoints' own sockets
# (bind port 0) are given theirs: a port picked there and released could be handed to one of
# them before the peer binds it (seen: MAVSDK's BIND_ERROR on a port "free" a moment earlier).
PORT_RANGE = (20000, 32000)


def free_udp_port() -> int:
    """A UDP port in ``PORT_RANGE`` that can be bound on 127.0.0.1 right now."""
    pick = random.SystemRandom()
    for _ in range(200):
        port = pick.randrange(*PORT_RANGE)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            try:
                sock.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError(f"no free UDP port in {PORT_RANGE[0]}-{PORT_RANGE[1]} on loopback")
