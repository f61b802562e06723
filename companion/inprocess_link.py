"""The in-process Link: direct calls into a vehicle_sim Simulator, in lockstep.

The loop's clock is the simulator's clock: ``sleep_until(t)`` steps the simulation to ``t``
(in whole physics steps), and nothing else advances it. Commands act at once. The same seed
and mission therefore give the same flight, bit for bit, however loaded the machine is.
This is the only companion module that imports vehicle_sim's simulator.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from collections.abc import Mapping, Sequence

import numpy as np

from companion.link import (
    STATUS_TEXTS_KEPT,
    CommandOutcome,
    LandedPhase,
    LinkError,
    LinkState,
    ObstacleDistances,
    StatusText,
    VelocityCommand,
)
from vehicle_sim import CommandResult, Simulator, load_sim_config
from vehicle_sim.vehicle_types import FlightMode, VehicleState, VelocitySetpoint


class SimClock:
    """Simulated time; sleeping advances the simulator (lockstep). Any simulator with
    ``state.t_s``, ``physics_dt_s`` and ``step(dt_s)`` will do (the multirotor's, the rover's)."""

    real_time = False

    def __init__(self, sim: Simulator) -> None:
        self._sim = sim

    def now_s(self) -> float:
        return float(self._sim.state.t_s)

    def sleep_until(self, t_s: float) -> None:
        dt_s = float(self._sim.physics_dt_s)
        steps = math.ceil((t_s - self.now_s()) / dt_s - 1e-6)
        if steps > 0:
            self._sim.step(steps * dt_s)


class InProcessLink:
    """A Link to a Simulator living in this process.

    Args:
        sim: the simulator to fly (the caller keeps ownership and may inspect it; its events,
            the texts a PX4 would send, are drained into ``status_texts`` at each read).
        metadata: extra sidecar entries (e.g. vehicle preset name, seed).
    """

    def __init__(self, sim: Simulator, metadata: Mapping[str, object] | None = None) -> None:
        self._sim = sim
        self._clock = SimClock(sim)
        self._metadata = dict(metadata or {})
        self._scan: ObstacleDistances | None = None
        self._status_texts: deque[StatusText] = deque(maxlen=STATUS_TEXTS_KEPT)

    @classmethod
    def from_vehicle(cls, vehicle: str, seed: int, world: object | None = None) -> InProcessLink:
        """A fresh simulator of preset (or config file) ``vehicle`` with ``seed``, in
        ``world`` (obstacles it can hit and its range sensor sees; see
        ``Simulator.set_world``) when given.

        Raises:
            SimConfigError: (a ValueError) unknown preset or bad config file, one line.
        """
        config = load_sim_config(vehicle)
        sim = Simulator(config, seed=seed)
        if world is not None:
            sim.set_world(world)
        return cls(sim, {"vehicle_preset": config.preset_name, "seed": seed})

    def _obstacle_distances(self) -> ObstacleDistances | None:
        """The simulator's range sensor, scanned at its own rate (None without a world)."""
        sensor = self._sim.range_sensor
        t_s = float(self._sim.t_s)
        if self._sim.world is None:
            return None
        if self._scan is None or t_s - self._scan.t_s >= 1.0 / sensor.rate_hz - 1e-9:
            scan = self._sim.range_scan()
            self._scan = ObstacleDistances(
                scan.t_s, scan.origin_ned_m, scan.angles_rad, scan.distances_m, scan.max_range_m
            )
        return self._scan

    @property
    def name(self) -> str:
        return "inprocess"

    @property
    def clock(self) -> SimClock:
        return self._clock

    def connect(self, timeout_s: float) -> None:
        if not _is_finite_state(self._sim.state):
            raise LinkError("in-process simulator has a non-finite state; cannot fly it")

    def read_state(self) -> LinkState:
        self._status_texts.extend(
            StatusText(self._clock.now_s(), text) for _, text in self._sim.drain_events()
        )
        state = link_state_of(self._sim.state)
        scan = self._obstacle_distances()
        return state if scan is None else dataclasses.replace(state, obstacle_distances=scan)

    def arm(self) -> CommandOutcome:
        return _outcome(self._sim.arm())

    def takeoff(self, alt_m: float) -> CommandOutcome:
        return _outcome(self._sim.takeoff(alt_m))

    def send_velocity(self, command: VelocityCommand) -> None:
        self._sim.set_velocity_setpoint(
            VelocitySetpoint(command.vel_ned_mps, yaw_rate_radps=command.yaw_rate_radps)
        )

    def start_offboard(self) -> CommandOutcome:
        return _outcome(self._sim.set_mode(FlightMode.OFFBOARD))

    def read_param(self, name: str) -> float | None:
        try:
            return float(self._sim.get_param(name))
        except ValueError:
            return None

    def stop_streaming(self) -> None:
        """Nothing streams in process: the simulator holds no periodic sender."""

    def hold(self) -> CommandOutcome:
        return _outcome(self._sim.set_mode(FlightMode.HOLD))

    def land(self) -> CommandOutcome:
        return _outcome(self._sim.land())

    @property
    def simulator(self) -> Simulator:
        """The simulated vehicle (for contact counts and truth after a flight)."""
        return self._sim

    def status_texts(self) -> Sequence[StatusText]:
        return tuple(self._status_texts)

    def metadata(self) -> Mapping[str, object]:
        contacts = {} if self._sim.world is None else {"contacts": len(self._sim.contacts)}
        return {
            "link": self.name,
            "mass_kg": float(self._sim.config.mass_kg),
            "physics_dt_s": float(self._sim.physics_dt_s),
            **contacts,
            **self._metadata,
        }

    def close(self) -> None:
        """Nothing to release: the simulator belongs to the caller."""


def link_state_of(s: VehicleState) -> LinkState:
    """The companion's view of a simulator state (all fields available in process)."""
    return LinkState(
        t_s=float(s.t_s),
        pos_ned_m=np.array(s.pos_ned_m, dtype=float),
        vel_ned_mps=np.array(s.vel_ned_mps, dtype=float),
        q_wxyz=np.array(s.q_wxyz, dtype=float),
        rates_frd_radps=np.array(s.rates_frd_radps, dtype=float),
        armed=bool(s.armed),
        mode=s.mode.name,
        landed=LandedPhase.of(s.landed_state),
        acc_ned_mps2=np.array(s.acc_ned_mps2, dtype=float),
        thrust_n=float(s.thrust_n),
        battery_v=float(s.battery_v),
        vehicle_kind="multirotor",
    )


def _is_finite_state(s: VehicleState) -> bool:
    parts = (s.pos_ned_m, s.vel_ned_mps, s.q_wxyz)
    return all(bool(np.all(np.isfinite(p))) for p in parts)


def _outcome(result: CommandResult) -> CommandOutcome:
    return CommandOutcome(bool(result.accepted), str(result.reason or ""))
