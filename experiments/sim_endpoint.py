"""Start and stop a `vehicle-sim` MAVLink endpoint as a child process (loopback, free ports).

Used by the demo to stand in for PX4 SITL: the companion then reaches it only over MAVLink,
as it would a real vehicle. The endpoint is always stopped on exit of the ``with`` block
(SIGINT, then SIGKILL after a deadline), also on errors and Ctrl-C.
"""

from __future__ import annotations

import random
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from types import TracebackType

_STOP_TIMEOUT_S = 10.0
_READY_TIMEOUT_S = 180.0  # a fresh checkout compiles the numba kernels first; a busy CPU slows it
_READY_LINE = b"Ctrl-C to stop"  # what vehicle-sim prints once its endpoint is running
_POLL_S = 0.1
SIM_RT_PRIORITY = 20
"""SCHED_FIFO priority of the endpoint's simulation loop: it stands in for a flight controller
on a processor of its own, which no program on the companion computer delays; above the
companion's control loop (companion.runner.COMPANION_RT_PRIORITY). Where the system does not
permit it, the endpoint's log says so and it runs at normal priority."""


class EndpointError(RuntimeError):
    """The endpoint process could not be started or died at once; one line."""


# Below Linux's ephemeral range (32768-60999), from which sockets bound to port 0 (a simulator
# endpoint's own, MAVSDK's) are given theirs: a port picked there and released could be handed
# to one of them before the peer binds it (seen: MAVSDK's BIND_ERROR on a port free a moment
# earlier, with tests beside that bind port 0).
PORT_RANGE = (20000, 32000)


def free_udp_ports(count: int) -> list[int]:
    """``count`` distinct UDP ports in ``PORT_RANGE`` that can be bound on 127.0.0.1 now
    (RuntimeError if 200 random tries do not find them)."""
    pick = random.SystemRandom()
    sockets: list[socket.socket] = []
    try:
        for _ in range(200):
            if len(sockets) == count:
                break
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            try:
                s.bind(("127.0.0.1", pick.randrange(*PORT_RANGE)))
            except OSError:
                s.close()
                continue
            sockets.append(s)
        if len(sockets) < count:
            raise RuntimeError(
                f"no {count} free UDP ports in {PORT_RANGE[0]}-{PORT_RANGE[1]} on loopback"
            )
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


class SimEndpoint:
    """``vehicle-sim --vehicle VEHICLE --seed SEED`` on free loopback ports, its simulation loop
    at ``realtime_priority`` (SCHED_FIFO; 0: normal priority); with ``onboard_log``, the
    vehicle's own flight log is written there when it stops.

    Attributes:
        mavsdk_url: where the companion's MAVSDK link listens (udpin://127.0.0.1:PORT).
        log_path: the endpoint's output (announcement and errors), kept for diagnosis.
    """

    def __init__(
        self,
        vehicle: str,
        seed: int,
        log_path: Path,
        onboard_log: Path | None = None,
        realtime_priority: int = SIM_RT_PRIORITY,
    ) -> None:
        offboard, gcs, offboard_bind, gcs_bind = free_udp_ports(4)
        self.mavsdk_url = f"udpin://127.0.0.1:{offboard}"
        self.log_path = log_path
        self._argv = [
            sys.executable, "-m", "scripts.vehicle_sim_cli", "--vehicle", vehicle,
            "--seed", str(seed), "--offboard-port", str(offboard), "--gcs-port", str(gcs),
            "--offboard-bind-port", str(offboard_bind), "--gcs-bind-port", str(gcs_bind),
            "--realtime-priority", str(realtime_priority),
        ]  # fmt: skip
        if onboard_log is not None:
            self._argv += ["--log", str(onboard_log)]
        self._process: subprocess.Popen[bytes] | None = None

    def __enter__(self) -> SimEndpoint:
        """Start it and wait until it serves (its announcement), so a companion connecting next
        finds it however long the start took."""
        self.log_path.parent.mkdir(parents=True, exist_ok=True)
        with self.log_path.open("wb") as out:
            self._process = subprocess.Popen(self._argv, stdout=out, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + _READY_TIMEOUT_S
        while _READY_LINE not in self.log_path.read_bytes():
            code = self._process.poll()
            if code is not None:
                raise EndpointError(f"vehicle-sim exited with code {code}; see {self.log_path}")
            if time.monotonic() > deadline:
                self.stop()
                raise EndpointError(
                    f"vehicle-sim not serving within {_READY_TIMEOUT_S:g} s; see {self.log_path}"
                )
            time.sleep(_POLL_S)
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    def stop(self) -> None:
        """SIGINT, wait up to a deadline, then SIGKILL; idempotent."""
        process, self._process = self._process, None
        if process is None or process.poll() is not None:
            return
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=_STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=_STOP_TIMEOUT_S)
