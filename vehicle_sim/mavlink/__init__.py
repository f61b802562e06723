"""MAVLink endpoint of the simulator: MAVLink 2 over UDP like PX4 SITL (docs/mavlink_protocol.md).

Start it in-process with ``MavlinkEndpoint(sim, EndpointConfig(...))`` (a context manager), or
from the command line with ``vehicle-sim``.
"""

from vehicle_sim.mavlink.config import EndpointConfig, LinkConfig, px4_sitl_links
from vehicle_sim.mavlink.endpoint import MavlinkEndpoint, PortTakenError, SetpointActuation
from vehicle_sim.mavlink.geodetic import GeodeticOrigin
from vehicle_sim.mavlink.signing import SigningKeyError, load_signing_key
from vehicle_sim.mavlink.stats import EndpointStats

__all__ = [
    "EndpointConfig",
    "EndpointStats",
    "GeodeticOrigin",
    "LinkConfig",
    "MavlinkEndpoint",
    "PortTakenError",
    "SetpointActuation",
    "SigningKeyError",
    "load_signing_key",
    "px4_sitl_links",
]
