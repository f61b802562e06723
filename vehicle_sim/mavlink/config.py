"""Configuration of the MAVLink endpoint: its UDP links, time scale and pacing."""

from __future__ import annotations

import math
from dataclasses import dataclass

from vehicle_sim.mavlink.geodetic import GeodeticOrigin

LOOPBACK = "127.0.0.1"


@dataclass(frozen=True)
class LinkConfig:
    """One UDP link (one socket), like one PX4 mavlink instance.

    Attributes:
        name: label used in stats and messages, e.g. "offboard" or "gcs".
        bind_host, bind_port: local address of the endpoint's socket (port 0: any free port).
        remote: (host, port) the endpoint sends to from the start, as PX4 SITL does towards
            14540/14550; None to wait for a client to speak first. Replies always go to the
            address a client's packets come from.
        signing_key: 32-byte MAVLink 2 signing secret; None leaves the link unsigned.
    """

    name: str
    bind_host: str = LOOPBACK
    bind_port: int = 0
    remote: tuple[str, int] | None = None
    signing_key: bytes | None = None

    def __post_init__(self) -> None:
        if not 0 <= self.bind_port <= 65535:
            raise ValueError(f"link {self.name}: bind_port must be 0..65535, got {self.bind_port}")
        if self.remote is not None and not 1 <= self.remote[1] <= 65535:
            raise ValueError(f"link {self.name}: remote port must be 1..65535, got {self.remote}")
        if self.signing_key is not None and len(self.signing_key) != 32:
            raise ValueError(f"link {self.name}: signing key must be 32 bytes")


def px4_sitl_links(
    offboard_port: int = 14540,
    gcs_port: int = 14550,
    host: str = LOOPBACK,
    signing_key: bytes | None = None,
    offboard_bind_port: int = 0,
    gcs_bind_port: int = 0,
) -> tuple[LinkConfig, ...]:
    """The two links PX4 SITL opens: the offboard API link (sends to 14540) and the GCS link
    (sends to 14550). PX4 binds 14580 and 18570; here the bind ports default to any free port."""
    return (
        LinkConfig("offboard", host, offboard_bind_port, (host, offboard_port), signing_key),
        LinkConfig("gcs", host, gcs_bind_port, (host, gcs_port), signing_key),
    )


@dataclass(frozen=True)
class EndpointConfig:
    """How the endpoint runs.

    Attributes:
        links: the UDP links (at least one); the first one's port is ``local_port``.
        speed: simulated seconds per wall-clock second (1.0 = real time).
        origin: geodetic position of the local NED origin / home.
        tick_s: wall-clock period of the pacing loop [s].
        max_lag_s: the longest wall-clock stall of the loop whose lost simulated time is caught
            up (the vehicle flies on through it); time lost beyond it is dropped, counted as an
            overrun: a process stopped that long was suspended, not just starved [s].
        heartbeat_min_hz: heartbeats per wall-clock second at least, whatever the speed
            (MAVSDK drops a link after 3 s without one).
    """

    links: tuple[LinkConfig, ...] = px4_sitl_links()
    speed: float = 1.0
    origin: GeodeticOrigin = GeodeticOrigin()
    tick_s: float = 0.004
    max_lag_s: float = 2.0
    heartbeat_min_hz: float = 1.0

    def __post_init__(self) -> None:
        if not self.links:
            raise ValueError("endpoint needs at least one link")
        names = [link.name for link in self.links]
        if len(set(names)) != len(names):
            raise ValueError(f"link names must be unique, got {names}")
        for field_name in ("speed", "tick_s", "max_lag_s", "heartbeat_min_hz"):
            value = getattr(self, field_name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{field_name} must be finite and > 0, got {value}")
