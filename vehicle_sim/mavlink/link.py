"""One UDP link of the endpoint: socket, codec, peers and its stream scheduler."""

from __future__ import annotations

import socket
import struct
import sys
import time
from collections import OrderedDict
from typing import NamedTuple

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
SO_TIMESTAMPNS_LINUX = 35
"""Linux's SO_TIMESTAMPNS (asm-generic/socket.h; Python does not name it): the kernel stamps
each datagram with its arrival time (CLOCK_REALTIME, struct timespec)."""
_TIMESPEC = struct.Struct("qq")


class Datagram(NamedTuple):
    """One received datagram and when it arrived (``time.perf_counter()`` seconds: the
    kernel's stamp where the system gives one, else the time it was read)."""

    data: bytes
    addr: Address
    arrived_s: float


class UdpLink:
    """A bound, non-blocking UDP socket with the peers it talks to.

    Peers are the configured remote (if any) plus every address a well-formed message came
    from. On Linux the kernel stamps each datagram's arrival, so a datagram read late (the
    process was starved of CPU) still says when it came. Socket errors (e.g. ICMP port
    unreachable from a peer that went away) are returned as False / None, never raised.
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
        self._stamped = sys.platform.startswith("linux")
        if self._stamped:
            try:
                self.sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS_LINUX, 1)
            except OSError:
                self._stamped = False

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

    def receive(self) -> Datagram | None:
        """One pending datagram, or None when there is none. Errors queued on the socket (ICMP
        port unreachable from a peer that went away) are skipped."""
        for _ in range(MAX_QUEUED_ERRORS):
            try:
                data, ancillary, _flags, addr = self.sock.recvmsg(
                    MAX_DATAGRAM_BYTES, socket.CMSG_SPACE(_TIMESPEC.size) if self._stamped else 0
                )
            except (BlockingIOError, InterruptedError):
                return None
            except OSError:
                continue
            return Datagram(data, (str(addr[0]), int(addr[1])), _arrival_s(ancillary))
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


def _arrival_s(ancillary: list[tuple[int, int, bytes]]) -> float:
    """The kernel's arrival stamp in ``time.perf_counter()`` seconds; now without one."""
    now_s = time.perf_counter()
    for level, kind, payload in ancillary:
        if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS_LINUX:
            seconds, nanoseconds = _TIMESPEC.unpack(payload[: _TIMESPEC.size])
            return min(now_s, now_s - (time.time() - (seconds + 1e-9 * nanoseconds)))
    return now_s
