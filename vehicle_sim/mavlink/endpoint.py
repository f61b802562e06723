"""The MAVLink endpoint: runs a Simulator in (scaled) real time behind UDP links, like PX4 SITL.

One background thread owns the simulator: it steps it to keep simulated time at
``speed x`` wall time, reads datagrams (setpoints are handed to the simulator at once, so the
next step acts on them), answers requests and streams telemetry. Nothing that arrives on a
socket can stop the loop: undecodable input is counted in ``stats``.

When the thread is starved of CPU (a busy computer), the simulated time it lost is caught up
afterwards, up to ``max_lag_s``, in passes of MAX_SIM_PER_PASS_S that do not sleep: the
simulator stands in for a flight controller on its own processor, whose vehicle flies on while
a companion is slow. Stopping the clock instead would freeze the vehicle while the companion's
wall-clock reference moves on. What arrived during the stall is acted on at the simulated time
it arrived (the kernel stamps each datagram, UdpLink), so a setpoint stream that kept coming is
not taken for a lost one (COM_OF_LOSS_T); without stamps (not Linux), at the time it is read.

In-process use (tests, benchmarks)::

    links = (LinkConfig("api", remote=("127.0.0.1", client_port)),)
    with MavlinkEndpoint(sim, EndpointConfig(links=links, speed=2.0)) as endpoint:
        ...  # MAVSDK: udpin://127.0.0.1:<client_port>
             # pymavlink: udpin:127.0.0.1:<client_port> or udpout:127.0.0.1:<endpoint.local_port>
"""

from __future__ import annotations

import errno
import math
import select
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim.mavlink.config import EndpointConfig
from vehicle_sim.mavlink.dispatcher import Dispatcher, Outgoing
from vehicle_sim.mavlink.link import Address, UdpLink
from vehicle_sim.mavlink.obstacle_distance import obstacle_distance_message
from vehicle_sim.mavlink.orbit import ORBIT_STATUS_PERIOD_S, orbit_execution_status
from vehicle_sim.mavlink.stats import EndpointStats, StatsCounter
from vehicle_sim.mavlink.statustext import CHUNK_ID_MAX, NoticeLimiter, statustext_chunks
from vehicle_sim.mavlink.telemetry import (
    TELEMETRY_BUILDERS,
    TelemetryContext,
    battery_cells_for,
    extended_sys_state,
    heartbeat,
)
from vehicle_sim.vehicle_types import VehicleState

if TYPE_CHECKING:
    from vehicle_sim import Simulator

MAX_DATAGRAMS_PER_PASS = 256
"""Datagrams read per link per loop pass, so a flood cannot starve the simulation."""
MAX_SIM_PER_PASS_S = 0.05
"""Simulated time stepped per loop pass at most [s of sim time at speed 1]."""
STALL_TICKS = 3
"""A datagram read more than this many loop ticks after its arrival was read late (the loop
was stalled); the simulation first catches up to its arrival."""
NOTICE_REPEAT_S = 1.0
"""A STATUSTEXT of one kind (see statustext.notice_kind) goes out at most once per this wall-clock
time [s]."""
NOTICE_MEMORY = 256
"""Distinct recent STATUSTEXT kinds remembered for the rate limit."""
TRACE_LENGTH = 4096
HEARTBEAT_ID = mavlink2.MAVLINK_MSG_ID_HEARTBEAT


class PortTakenError(OSError):
    """A link's own UDP port could not be bound (another simulator or PX4 SITL may hold it);
    ``link_name`` is the LinkConfig's name ("offboard", "gcs")."""

    def __init__(self, link_name: str, message: str) -> None:
        super().__init__(message)
        self.link_name = link_name


@dataclass(frozen=True)
class SetpointActuation:
    """When a setpoint, received in OFFBOARD, was first acted on by the simulation.

    Attributes:
        time_boot_ms: the setpoint message's own ``time_boot_ms`` (a client's marker).
        received_s: ``time.perf_counter()`` when its datagram was read [s].
        actuated_s: ``time.perf_counter()`` when the first simulation step using it ended [s].
    """

    time_boot_ms: int
    received_s: float
    actuated_s: float


class MavlinkEndpoint:
    """A Simulator behind MAVLink UDP links.

    Args:
        sim: the simulator; from ``start()`` to ``stop()`` it belongs to the endpoint's thread
            (read ``state`` instead of touching it).
        config: links, speed and pacing; default: PX4 SITL's two links on loopback.
    """

    def __init__(self, sim: Simulator, config: EndpointConfig | None = None) -> None:
        self.sim = sim
        self.config = config if config is not None else EndpointConfig()
        self._stats = StatsCounter()
        self._links: list[UdpLink] = []
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._state: VehicleState = sim.state
        self._telemetry = TelemetryContext(
            origin=self.config.origin, battery_cells=battery_cells_for(sim.state.battery_v)
        )
        self._dispatcher = Dispatcher(sim, self._telemetry, self._stats, self._on_setpoint)
        self._received_s = 0.0
        self._wall0_s = 0.0  # pacing origin: wall-clock time (perf_counter) ...
        self._sim0_s = 0.0  # ... and the simulated time it stands for [s]
        self._pending: list[tuple[int, float]] = []
        self._obstacles_due_s = 0.0  # next OBSTACLE_DISTANCE [s of simulated time]
        self._orbit_due_s = 0.0  # next ORBIT_EXECUTION_STATUS [s of simulated time]
        self._trace: deque[SetpointActuation] = deque(maxlen=TRACE_LENGTH)
        self._notice_limiter = NoticeLimiter(NOTICE_REPEAT_S, NOTICE_MEMORY)
        self._factory = mavlink2.MAVLink(None)
        self._mission_seen: tuple[object, ...] | None = None
        self._mission_sent_s = -math.inf
        self._chunk_id = 0
        self._heartbeat_wall_s: dict[str, float] = {}

    # -- lifecycle ----------------------------------------------------------------------------

    def start(self) -> MavlinkEndpoint:
        """Bind the sockets (PortTakenError naming the link if its port is taken, OSError naming it
        for another failure, e.g. an address this machine does not have), run one physics
        step (the simulator's first step compiles its kernels, which may take seconds; done
        here, the real-time loop starts without lag) and start the loop."""
        if self._thread is not None:
            raise RuntimeError("endpoint already started")
        for link_config in self.config.links:
            try:
                self._links.append(UdpLink(link_config))
            except OSError as exc:
                self._close_links()
                what = (
                    f"cannot bind link {link_config.name} to "
                    f"{link_config.bind_host}:{link_config.bind_port}: {exc.strerror or exc}"
                )
                if exc.errno == errno.EADDRINUSE:
                    raise PortTakenError(link_config.name, what) from None
                raise OSError(what) from None
        self._state = self.sim.step(self.sim.physics_dt_s)
        self._thread = threading.Thread(target=self._run, name="mavlink-endpoint", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout_s: float = 10.0) -> None:
        """Stop the loop and close the sockets; re-raises (as RuntimeError) a loop failure."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
            if self._thread.is_alive():
                raise RuntimeError(f"endpoint loop did not stop within {timeout_s} s")
        self._close_links()
        if self._error is not None:
            raise RuntimeError(f"endpoint loop failed: {self._error!r}") from self._error

    def __enter__(self) -> MavlinkEndpoint:
        return self.start()

    def __exit__(self, *_exc: object) -> None:
        self.stop()

    def _close_links(self) -> None:
        for link in self._links:
            link.close()
        self._links = []

    # -- what callers read --------------------------------------------------------------------

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @property
    def loop_thread_id(self) -> int | None:
        """Native id of the loop's thread (``threading.get_native_id`` in it), None before
        ``start()``: to give the loop a scheduling priority from outside."""
        return None if self._thread is None else self._thread.native_id

    @property
    def local_port(self) -> int:
        """UDP port of the first link (clients may send there: ``udpout:127.0.0.1:PORT``)."""
        return self._links[0].local_port

    @property
    def local_ports(self) -> dict[str, int]:
        """Bound UDP port of every link, by link name."""
        return {link.config.name: link.local_port for link in self._links}

    @property
    def stats(self) -> EndpointStats:
        return self._stats.snapshot()

    @property
    def state(self) -> VehicleState:
        """The simulator's latest state (safe to read from any thread); it already reflects
        every command whose COMMAND_ACK was sent."""
        return self._state

    def setpoint_trace(self) -> tuple[SetpointActuation, ...]:
        """The latest setpoint actuations (up to 4096), oldest first."""
        return tuple(self._trace)

    # -- the loop -----------------------------------------------------------------------------

    def _run(self) -> None:
        try:
            self._loop()
        except Exception as exc:  # reported by stop(); the thread must not die silently
            self._error = exc

    def _loop(self) -> None:
        cfg = self.config
        dt_s = float(self.sim.physics_dt_s)
        max_steps = max(1, math.ceil(MAX_SIM_PER_PASS_S * cfg.speed / dt_s))
        self._wall0_s, self._sim0_s = time.perf_counter(), self.sim.state.t_s
        flags: tuple[object, ...] | None = None
        sockets = [link.sock for link in self._links]
        while not self._stop.is_set():
            now_s = time.perf_counter()
            state = self.sim.state
            behind_s = self._sim_time_at(now_s) - state.t_s
            if behind_s > cfg.max_lag_s * cfg.speed:
                self._stats.add("loop_overruns")
                self._sim0_s += behind_s - cfg.max_lag_s * cfg.speed  # drop the excess only
                behind_s = cfg.max_lag_s * cfg.speed
            steps_behind = math.floor(behind_s / dt_s + 1e-6)
            catching_up = steps_behind > max_steps
            n_steps = min(max_steps, steps_behind)
            if n_steps > 0:
                state = self.sim.step(n_steps * dt_s)
                self._mark_actuated(time.perf_counter())
                if catching_up:
                    self._stats.add("caught_up_ms", round(1e3 * n_steps * dt_s))
            self._state = state
            for severity, text in self.sim.drain_events():
                self._notice(severity, text)
            self._mission_progress(state, now_s)
            new_flags = (state.armed, state.mode, state.landed_state)
            if new_flags != flags:
                flags = new_flags
                self._broadcast(heartbeat(state, self._telemetry))
                self._broadcast(extended_sys_state(state, self._telemetry))
            self._stream(state, time.perf_counter())
            self._stream_obstacles(state)
            self._stream_orbit(state)
            wait_s = 0.0 if catching_up else cfg.tick_s  # no sleeping while behind
            readable, _, _ = select.select(sockets, [], [], wait_s)
            for link in self._links:
                if link.sock in readable:
                    self._drain(link)

    def _sim_time_at(self, wall_s: float) -> float:
        """Simulated time [s] that ``wall_s`` (``time.perf_counter()``) stands for."""
        return self._sim0_s + (wall_s - self._wall0_s) * self.config.speed

    def _catch_up_to(self, arrived_s: float) -> None:
        """Before acting on a datagram that arrived while the loop was stalled (the simulation
        more than STALL_TICKS ticks behind its arrival), fly the vehicle on to the simulated
        time it arrived at, so that it acts on it then: neither early nor as if the setpoint
        stream had stopped (COM_OF_LOSS_T)."""
        dt_s = float(self.sim.physics_dt_s)
        cfg = self.config
        behind_s = min(self._sim_time_at(arrived_s) - self.sim.t_s, cfg.max_lag_s * cfg.speed)
        if behind_s > STALL_TICKS * cfg.tick_s * cfg.speed:
            steps = math.floor(behind_s / dt_s + 1e-6)
            self._state = self.sim.step(steps * dt_s)
            self._mark_actuated(time.perf_counter())
            self._stats.add("caught_up_ms", round(1e3 * steps * dt_s))

    def _mission_progress(self, state: VehicleState, wall_s: float) -> None:
        """MISSION_ITEM_REACHED as items are reached; MISSION_CURRENT on a change and at 1 Hz."""
        reached = self.sim.drain_mission_reached()
        for seq in reached:
            self._broadcast(self._factory.mission_item_reached_encode(seq))
        current = (self.sim.mission_current, len(self.sim.mission), state.mode)
        if reached or current != self._mission_seen or wall_s >= self._mission_sent_s + 1.0:
            self._mission_seen, self._mission_sent_s = current, wall_s
            self._broadcast(self._dispatcher.missions.current_message())

    def _stream(self, state: VehicleState, wall_s: float) -> None:
        heartbeat_period_s = 1.0 / self.config.heartbeat_min_hz
        for link in self._links:
            due = link.scheduler.due(state.t_s)
            name = link.config.name
            since_heartbeat_s = wall_s - self._heartbeat_wall_s.get(name, -math.inf)
            if since_heartbeat_s >= heartbeat_period_s and HEARTBEAT_ID not in due:
                due = [HEARTBEAT_ID, *due]  # wall-clock guard; re-phase the sim-time stream
                link.scheduler.restart(HEARTBEAT_ID, state.t_s)
            if HEARTBEAT_ID in due:
                self._heartbeat_wall_s[name] = wall_s
            for msg_id in due:
                try:
                    msg = TELEMETRY_BUILDERS[msg_id](state, self._telemetry)
                except (ValueError, OverflowError):
                    self._stats.add("handler_errors")
                    continue
                self._send_to_peers(link, msg)

    def _stream_obstacles(self, state: VehicleState) -> None:
        """OBSTACLE_DISTANCE at the range sensor's rate of simulated time, when the vehicle
        flies in a world (vehicle_sim.world_contact)."""
        if self.sim.world is None:
            return
        sensor = self.sim.range_sensor
        if state.t_s < self._obstacles_due_s:
            return
        self._obstacles_due_s = state.t_s + 1.0 / sensor.rate_hz
        msg = obstacle_distance_message(self.sim.range_scan(), sensor.min_range_m)
        for link in self._links:
            self._send_to_peers(link, msg)

    def _stream_orbit(self, state: VehicleState) -> None:
        """ORBIT_EXECUTION_STATUS at 2 Hz of simulated time while the vehicle orbits."""
        orbit = self.sim.orbit_status
        if orbit is None or state.t_s < self._orbit_due_s:
            return
        self._orbit_due_s = state.t_s + ORBIT_STATUS_PERIOD_S
        try:
            msg = orbit_execution_status(orbit, self._telemetry.origin, state.t_s)
        except ValueError:
            self._stats.add("handler_errors")
            return
        self._broadcast(msg)

    def _drain(self, link: UdpLink) -> None:
        for _ in range(MAX_DATAGRAMS_PER_PASS):
            item = link.receive()
            if item is None:
                return
            data, addr, arrived_s = item
            self._catch_up_to(arrived_s)
            self._received_s = time.perf_counter()
            self._stats.add("datagrams_received")
            decoded = link.codec.decode(data)
            self._stats.add("bad_frames", decoded.bad_frames)
            self._stats.add("signing_rejected", decoded.signing_rejected)
            self._stats.add("truncated_datagrams", int(decoded.truncated))
            if not decoded.messages:
                if not decoded.signing_rejected:
                    self._stats.add("garbage_datagrams")
                continue
            link.heard_from(addr)
            now_ns = int(self._state.t_s * 1e9)
            for msg in decoded.messages:
                self._stats.add("messages_received")
                outgoing = self._dispatcher.handle(msg, link.scheduler, now_ns)
                self._state = self.sim.state  # an ACK's effect is visible once it is sent
                self._send_outgoing(link, addr, outgoing)

    # -- sending ------------------------------------------------------------------------------

    def _send_outgoing(self, link: UdpLink, addr: Address, outgoing: list[Outgoing]) -> None:
        for item in outgoing:
            if item.notice is not None:
                self._notice(*item.notice)
            elif item.broadcast:
                self._broadcast(item.msg)
            else:
                self._send(link, link.codec.encode(item.msg), addr)

    def _notice(self, severity: int, text: str) -> None:
        """Broadcast a STATUSTEXT (chunked if long) unless one of its kind went out lately."""
        if not self._notice_limiter.allow(text, time.perf_counter()):
            self._stats.add("notices_suppressed")
            return
        self._stats.add("notices_sent")
        self._chunk_id = self._chunk_id % CHUNK_ID_MAX + 1
        for msg in statustext_chunks(severity, text, self._chunk_id):
            self._broadcast(msg)

    def _broadcast(self, msg: mavlink2.MAVLink_message) -> None:
        for link in self._links:
            self._send_to_peers(link, msg)

    def _send_to_peers(self, link: UdpLink, msg: mavlink2.MAVLink_message) -> None:
        data = link.codec.encode(msg)
        for peer in link.peers():
            self._send(link, data, peer)

    def _send(self, link: UdpLink, data: bytes, addr: Address) -> None:
        if link.send(data, addr):
            self._stats.add("messages_sent")
        else:
            self._stats.add("send_errors")

    # -- setpoint latency trace ---------------------------------------------------------------

    def _on_setpoint(self, time_boot_ms: int) -> None:
        self._pending.append((time_boot_ms, self._received_s))

    def _mark_actuated(self, actuated_s: float) -> None:
        for time_boot_ms, received_s in self._pending:
            self._trace.append(SetpointActuation(time_boot_ms, received_s, actuated_s))
        self._pending.clear()
