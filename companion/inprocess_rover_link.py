"""The in-process Link to a ground rover: direct calls into a vehicle_sim RoverSim, in lockstep.

The rover counterpart of companion.inprocess_link, speaking what PX4 rovers accept in offboard
([PX4-rover]): a NED velocity setpoint (projected on the heading: a rover drives forward or
back, it cannot slide) and a yaw rate. The rover's world frame has x north and y west with
heading counter-clockwise from x (vehicle_sim.rover.mavlink_rover), so NED north = x_m,
east = -y_m and yaw = -heading_rad. Takeoff and land do not apply to a rover and are refused.
Nothing here imports vehicle_sim at module level: the simulator object is handed in, or
:meth:`InProcessRoverLink.from_preset` imports it when called.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from companion.inprocess_link import SimClock
from companion.link import (
    CommandOutcome,
    LandedPhase,
    LinkError,
    LinkState,
    StatusText,
    VelocityCommand,
)


class InProcessRoverLink:
    """A Link to a ``vehicle_sim.rover.RoverSim`` living in this process.

    Args:
        sim: the rover simulator (the caller keeps ownership and may inspect it).
        metadata: extra sidecar entries (e.g. preset name, seed).
    """

    def __init__(self, sim: Any, metadata: Mapping[str, object] | None = None) -> None:
        self._sim = sim
        self._clock = SimClock(sim)
        self._metadata = dict(metadata or {})
        self._offboard = False
        self._have_setpoint = False

    @classmethod
    def from_preset(cls, preset: str, seed: int = 0) -> InProcessRoverLink:
        """A fresh RoverSim of ``preset`` (husky_50kg, roc6_150kg, dmrv_600kg) with ``seed``."""
        from vehicle_sim.rover import RoverSim, rover_preset  # lazy: companion installs alone

        return cls(
            RoverSim(rover_preset(preset), seed=seed), {"rover_preset": preset, "seed": seed}
        )

    @property
    def name(self) -> str:
        return "inprocess"

    @property
    def clock(self) -> SimClock:
        return self._clock

    def connect(self, timeout_s: float) -> None:
        st = self._sim.state
        if not all(math.isfinite(v) for v in (st.x_m, st.y_m, st.heading_rad)):
            raise LinkError("in-process rover has a non-finite state; cannot drive it")

    def read_state(self) -> LinkState:
        st = self._sim.state
        c, s = math.cos(st.heading_rad), math.sin(st.heading_rad)
        vx = st.speed_mps * c - st.lat_speed_mps * s
        vy = st.speed_mps * s + st.lat_speed_mps * c
        yaw = -st.heading_rad
        return LinkState(
            t_s=float(st.t_s),
            pos_ned_m=np.array([st.x_m, -st.y_m, 0.0]),
            vel_ned_mps=np.array([vx, -vy, 0.0]),
            q_wxyz=np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]),
            rates_frd_radps=np.array([0.0, 0.0, -st.yaw_rate_radps]),
            armed=bool(self._sim.armed),
            mode="OFFBOARD" if self._offboard else "HOLD",
            landed=LandedPhase.ON_GROUND,
            vehicle_kind="rover",
        )

    def arm(self) -> CommandOutcome:
        self._sim.arm()
        return CommandOutcome(True)

    def takeoff(self, alt_m: float) -> CommandOutcome:
        return CommandOutcome(False, "a ground rover does not take off")

    def send_velocity(self, command: VelocityCommand) -> None:
        self._have_setpoint = True
        if not (self._offboard and self._sim.armed):
            return
        vn, ve, _ = command.vel_ned_mps
        yaw = -self._sim.state.heading_rad
        speed = vn * math.cos(yaw) + ve * math.sin(yaw)
        self._sim.set_setpoint(float(speed), -float(command.yaw_rate_radps))

    def start_offboard(self) -> CommandOutcome:
        if not self._have_setpoint:
            return CommandOutcome(False, "no setpoint streamed before OFFBOARD")
        self._offboard = True
        return CommandOutcome(True)

    def read_param(self, name: str) -> float | None:
        return None

    def stop_streaming(self) -> None:
        """Nothing streams in process."""

    def hold(self) -> CommandOutcome:
        self._offboard = False
        self._sim.set_setpoint(0.0, 0.0)
        return CommandOutcome(True)

    def land(self) -> CommandOutcome:
        return CommandOutcome(False, "a ground rover does not land; use hold")

    def status_texts(self) -> Sequence[StatusText]:
        """None: the rover simulator has no failsafes or notices of its own in process."""
        return ()

    def metadata(self) -> Mapping[str, object]:
        return {
            "link": self.name,
            "mass_kg": float(self._sim.preset.mass_kg),
            "physics_dt_s": float(self._sim.physics_dt_s),
            **self._metadata,
        }

    def close(self) -> None:
        """Nothing to release: the simulator belongs to the caller."""
