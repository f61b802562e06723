"""One UDP link of the endpoint: socket, codec, peers and its stream scheduler."""

from __future__ import annotations

import socket
from collections import OrderedDict

from vehicle_sim.mavlink.codec import LinkCodec
from vehicle_sim.mavlink.config import LinkConfig
from vehicle_sim.mavlink.scheduler import RateScheduler
from vehicle_sim.mavlink.telemetry import DEFAULT_RATES_HZ

Address = tuple[str, int]

MAX_PEERS = 8
"""Clients remembered per link; the least recently heard one is forgotten first."""
RECEIVE_BUFFER_BYTES = 1 << 20
MAX_DATAGRAM_BYTES = 65535
MAX_QUEUED_ERRORS = 8


class UdpLink:
    """A bound, non-blocking UDP socket with the peers it talks to.

    Peers are the configured remote (if any) plus every address a well-formed message came
    from. Socket errors (e.g. ICMP port unreachable from a peer that went away) are returned as
    False / None, never raised.
    """

    def __init__(self, config: LinkConfig) -> None:
        self.config = config
        self.codec = LinkCodec(config.signing_key)
        self.scheduler = RateScheduler(DEFAULT_RATES_HZ)
        self._peers: OrderedDict[Address, None] = OrderedDict()
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER_BYTES)
            self.sock.bind((config.bind_host, config.bind_port))
        except OSError:
            self.sock.close()
            raise
        self.sock.setblocking(False)

    @property
    def local_port(self) -> int:
        return int(self.sock.getsockname()[1])

    def peers(self) -> list[Address]:
        """Where telemetry goes: the configured remote first, then clients heard from."""
        remote = [self.config.remote] if self.config.remote is not None else []
        return remote + [addr for addr in self._peers if addr not in remote]

    def heard_from(self, addr: Address) -> None:
        """Remember a client that sent a well-formed message."""
        self._peers[addr] = None
        self._peers.move_to_end(addr)
        while len(self._peers) > MAX_PEERS:
            self._peers.popitem(last=False)

    def receive(self) -> tuple[bytes, Address] | None:
        """One pending datagram, or None when there is none. Errors queued on the socket (ICMP
        port unreachable from a peer that went away) are skipped."""
        for _ in range(MAX_QUEUED_ERRORS):
            try:
                data, addr = self.sock.recvfrom(MAX_DATAGRAM_BYTES)
            except (BlockingIOError, InterruptedError):
                return None
            except OSError:
                continue
            return data, (str(addr[0]), int(addr[1]))
        return None

    def send(self, data: bytes, addr: Address) -> bool:
        """Send one datagram; False when the socket refused it."""
        try:
            self.sock.sendto(data, addr)
        except OSError:
            return False
        return True

    def close(self) -> None:
        self.sock.close()
