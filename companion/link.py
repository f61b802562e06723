"""The one interface the control loop sees: a `Link` to a vehicle, and the values it exchanges.

A Link hides how the vehicle is reached (MAVSDK, pymavlink, or direct calls into an in-process
simulator). Everything crossing it is SI and local NED / body FRD, as PX4 does; wire units stay
inside the implementations. Every Link also brings its `Clock`: the wall clock for real links,
the simulator's clock for the in-process one (lockstep), so the same loop code runs on all.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal, Protocol, get_args

import numpy as np

from flightlog import px4

VehicleKind = Literal["multirotor", "VTOL", "fixed wing", "rover", "boat", "other"]
# MAV_TYPE values (MAVLink common.xml) of each kind; "other" is every type not listed
_KINDS_OF_MAV_TYPE: dict[int, VehicleKind] = {
    **dict.fromkeys(px4.MAV_TYPE_MULTIROTOR, "multirotor"),  # quad .. decarotor, heli
    **dict.fromkeys(px4.MAV_TYPE_VTOL, "VTOL"),
    1: "fixed wing",
    px4.MAV_TYPE_GROUND_ROVER: "rover",
    11: "boat",
}


def vehicle_kind(mav_type: int) -> VehicleKind:
    """The kind of vehicle a HEARTBEAT's MAV_TYPE names (PX4 sends its airframe's)."""
    return _KINDS_OF_MAV_TYPE.get(int(mav_type), "other")


FlightModeName = Literal[
    "MANUAL", "POSCTL", "ALTCTL", "HOLD", "TAKEOFF", "LAND", "RTL", "MISSION", "OFFBOARD", "ORBIT",
    "STABILIZED", "ACRO", "UNKNOWN",
]  # fmt: skip
FLIGHT_MODE_NAMES: tuple[str, ...] = get_args(FlightModeName)


class LandedPhase(enum.IntEnum):
    """MAVLink MAV_LANDED_STATE values, as the flight controller reports them."""

    UNKNOWN = 0
    ON_GROUND = 1
    IN_AIR = 2
    TAKEOFF = 3
    LANDING = 4

    @classmethod
    def of(cls, value: int) -> LandedPhase:
        """The phase for a MAV_LANDED_STATE value; UNKNOWN for values outside the enum."""
        try:
            return cls(int(value))
        except ValueError:
            return cls.UNKNOWN


class LinkError(RuntimeError):
    """The link cannot do what was asked (no vehicle, timeout, refused); one-line message."""


@dataclass(frozen=True)
class ObstacleDistances:
    """A horizontal range scan, as MAVLink OBSTACLE_DISTANCE carries it ([MAVLink]), in SI.

    Attributes:
        t_s: when it was measured, on the link's clock [s].
        origin_ned_m: (3,) sensor position (the vehicle's, at measurement) [m].
        angles_rad: (k,) beam directions from north, clockwise seen from above (towards east).
        distances_m: (k,) range per beam [m]; inf where nothing is within ``max_range_m``.
        max_range_m: the sensor's range [m].
    """

    t_s: float
    origin_ned_m: np.ndarray
    angles_rad: np.ndarray
    distances_m: np.ndarray
    max_range_m: float


@dataclass(frozen=True)
class LinkState:
    """A telemetry snapshot, as the companion sees it.

    Attributes:
        t_s: time of the snapshot on the link's clock [s].
        pos_ned_m, vel_ned_mps: (3,) local NED position [m] and velocity [m/s].
        q_wxyz: (4,) attitude quaternion, body FRD to NED.
        rates_frd_radps: (3,) body angular rates [rad/s].
        armed: the flight controller is armed.
        mode: PX4 flight mode name, one of FLIGHT_MODE_NAMES.
        landed: landed phase reported by the flight controller.
        acc_ned_mps2: (3,) measured acceleration [m/s^2], or None when the link has none.
        thrust_n: total rotor thrust [N], or None when the link has none.
        battery_v: battery voltage [V], or None when unknown.
        obstacle_distances: the newest range scan, or None when the link has no range sensor.
        vehicle_kind: what the vehicle is, from its HEARTBEAT's MAV_TYPE (:func:`vehicle_kind`),
            or None when the link does not say (MAVSDK's API does not give it).
    """

    t_s: float
    pos_ned_m: np.ndarray
    vel_ned_mps: np.ndarray
    q_wxyz: np.ndarray
    rates_frd_radps: np.ndarray
    armed: bool
    mode: FlightModeName
    landed: LandedPhase
    acc_ned_mps2: np.ndarray | None = None
    thrust_n: float | None = None
    battery_v: float | None = None
    obstacle_distances: ObstacleDistances | None = None
    vehicle_kind: VehicleKind | None = None

    @property
    def yaw_rad(self) -> float:
        """Heading [rad] from the quaternion (NED, clockwise from north)."""
        w, x, y, z = self.q_wxyz
        return float(math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))

    @property
    def altitude_m(self) -> float:
        """Height above the local origin [m] (= -down)."""
        return float(-self.pos_ned_m[2])

    def is_finite(self) -> bool:
        """True if position, velocity, attitude and rates are all finite."""
        parts = (self.pos_ned_m, self.vel_ned_mps, self.q_wxyz, self.rates_frd_radps)
        return all(bool(np.all(np.isfinite(p))) for p in parts)


@dataclass(frozen=True)
class VelocityCommand:
    """What the companion streams: NED velocity [m/s] and yaw rate [rad/s]."""

    vel_ned_mps: tuple[float, float, float]
    yaw_rate_radps: float = 0.0

    def __post_init__(self) -> None:
        values = (*self.vel_ned_mps, self.yaw_rate_radps)
        if len(self.vel_ned_mps) != 3 or not all(math.isfinite(v) for v in values):
            raise ValueError(
                f"velocity command must be 3 finite NED components and a finite yaw rate, "
                f"got vel_ned_mps={self.vel_ned_mps}, yaw_rate_radps={self.yaw_rate_radps}"
            )


ZERO_VELOCITY = VelocityCommand((0.0, 0.0, 0.0), 0.0)


STATUS_TEXTS_KEPT = 32
"""How many of the vehicle's latest texts a Link keeps (Link.status_texts)."""


@dataclass(frozen=True)
class StatusText:
    """A text the vehicle sent (MAVLink STATUSTEXT; PX4's user messages, its failsafes' too).

    Attributes:
        t_s: when it arrived, on the Link's clock [s].
        text: what it said.
    """

    t_s: float
    text: str


@dataclass(frozen=True)
class CommandOutcome:
    """Answer to a vehicle command: accepted or not, and why (the autopilot's words)."""

    accepted: bool
    detail: str = ""


class Clock(Protocol):
    """Time as the control loop uses it.

    Attributes:
        real_time: True when sleeping waits for the wall clock (the loop then sleeps between
            ticks and may run at a real-time priority, companion.realtime); False in lockstep.
    """

    real_time: bool

    def now_s(self) -> float:
        """Current time [s] (monotonic; origin is the clock's own)."""
        ...

    def sleep_until(self, t_s: float) -> None:
        """Return once ``now_s() >= t_s`` (at once if that is already so).

        A wall clock sleeps (and may keep the link serviced meanwhile); a lockstep clock
        advances the simulated vehicle to ``t_s``.
        """
        ...


class Link(Protocol):
    """A connection to one vehicle. Commands block until answered or their deadline passes."""

    @property
    def name(self) -> str:
        """Short name for logs and messages: "mavsdk", "pymavlink" or "inprocess"."""
        ...

    @property
    def clock(self) -> Clock:
        """The clock the loop must run on for this link."""
        ...

    def connect(self, timeout_s: float) -> None:
        """Wait until the vehicle is seen and telemetry flows; raises LinkError after timeout_s."""
        ...

    def read_state(self) -> LinkState:
        """The newest telemetry snapshot (never blocks for long)."""
        ...

    def arm(self) -> CommandOutcome: ...

    def takeoff(self, alt_m: float) -> CommandOutcome:
        """Climb to ``alt_m`` above the origin and hold there (PX4 takeoff mode)."""
        ...

    def send_velocity(self, command: VelocityCommand) -> None:
        """Stream one velocity setpoint (proof of life; flown only in OFFBOARD)."""
        ...

    def start_offboard(self) -> CommandOutcome:
        """Switch to OFFBOARD; the caller must have streamed setpoints first."""
        ...

    def read_param(self, name: str) -> float | None:
        """The autopilot's value of PX4 parameter ``name``, or None when it does not answer
        (an autopilot without it, or a link that cannot ask)."""
        ...

    def stop_streaming(self) -> None:
        """Stop sending setpoints and command nothing: the vehicle is handed over to whoever
        switched it out of OFFBOARD (a pilot or a ground station)."""
        ...

    def hold(self) -> CommandOutcome:
        """Stop streaming setpoints and switch to HOLD (PX4 "Hold"/loiter)."""
        ...

    def land(self) -> CommandOutcome:
        """Land at the current position; PX4 disarms after touchdown."""
        ...

    def status_texts(self) -> Sequence[StatusText]:
        """The vehicle's latest texts since connecting, oldest first (the last
        STATUS_TEXTS_KEPT)."""
        ...

    def metadata(self) -> Mapping[str, object]:
        """What the flight log sidecar should record about this link (source, url, mass_kg...)."""
        ...

    def close(self) -> None:
        """Release sockets and threads; idempotent."""
        ...
