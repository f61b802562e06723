"""Benchmark of the MAVLink endpoint on loopback: telemetry rates and setpoint latency.

A pymavlink client flies the endpoint (real time) to a hover in OFFBOARD while streaming
velocity setpoints at 50 Hz, as the companion does, and records every telemetry message's
arrival. Figures:

- ``telemetry_rate_error_max_fraction``: worst |measured / nominal - 1| over the streams of
  at least 1 Hz (rates from first-to-last arrival time, so 1 Hz streams are not quantised);
- ``setpoint_latency_median_ms`` / ``_p99_ms``: from the client's send of a setpoint to the end
  of the first simulation step acting on it (the setpoint's ``time_boot_ms`` carries a sequence
  number; the endpoint's setpoint trace gives the actuation time on the same clock);
- ``setpoint_rate_hz``: setpoints the endpoint accepted per second during the window.
"""

from __future__ import annotations

import os
import threading
import time
from collections import defaultdict
from collections.abc import Callable

import numpy as np

os.environ["MAVLINK20"] = "1"

from pymavlink import mavutil  # noqa: E402

from vehicle_sim import FlightMode, Simulator, load_sim_config  # noqa: E402
from vehicle_sim.mavlink import EndpointConfig, LinkConfig, MavlinkEndpoint  # noqa: E402
from vehicle_sim.mavlink.telemetry import DEFAULT_RATES_HZ  # noqa: E402

SETPOINT_RATE_HZ = 50.0
MASK_VELOCITY_YAW_RATE = 1479
WAIT_S = 20.0


def _wait(predicate: Callable[[], bool], what: str, timeout_s: float = WAIT_S) -> None:
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise RuntimeError(f"bench_link: timed out waiting for {what}")
        time.sleep(0.01)


class _Client:
    """pymavlink client: a receiver thread logging arrivals, a 50 Hz setpoint thread."""

    def __init__(self, port: int) -> None:
        self.conn = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{port}", source_system=245, source_component=190, dialect="common"
        )
        self.lock = threading.Lock()
        self.arrivals: dict[str, list[float]] = defaultdict(list)
        self.acks: dict[int, int] = {}
        self.sent_s: dict[int, float] = {}
        self.stop = threading.Event()
        self.streaming = threading.Event()
        self.threads = [threading.Thread(target=f, daemon=True) for f in (self._rx, self._tx)]
        for thread in self.threads:
            thread.start()

    def _rx(self) -> None:
        while not self.stop.is_set():
            msg = self.conn.recv_match(blocking=True, timeout=0.1)
            if msg is None:
                continue
            self.arrivals[msg.get_type()].append(time.perf_counter())
            if msg.get_type() == "COMMAND_ACK":
                self.acks[msg.command] = msg.result

    def _tx(self) -> None:
        seq = 0
        next_s = time.perf_counter()
        while not self.stop.is_set():
            with self.lock:
                if self.streaming.is_set():
                    seq += 1
                    self.sent_s[seq] = time.perf_counter()
                    self.conn.mav.set_position_target_local_ned_send(
                        seq, 1, 1, 1, MASK_VELOCITY_YAW_RATE, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0
                    )
                else:
                    self.conn.mav.heartbeat_send(6, 8, 0, 0, 0)
            next_s += 1.0 / SETPOINT_RATE_HZ
            time.sleep(max(0.0, next_s - time.perf_counter()))

    def command(self, command: int, *params: float) -> int:
        p = list(params) + [float("nan")] * (7 - len(params))
        self.acks.pop(command, None)
        with self.lock:
            self.conn.mav.command_long_send(1, 1, command, 0, *p)
        _wait(lambda: command in self.acks, f"COMMAND_ACK {command}", 5.0)
        return self.acks[command]

    def close(self) -> None:
        self.stop.set()
        for thread in self.threads:
            thread.join(2.0)
        self.conn.close()


def _rate_errors(
    arrivals: dict[str, list[float]], start_s: float, end_s: float
) -> dict[str, float]:
    """Stream name -> |measured rate / nominal rate - 1| within [start_s, end_s]."""
    errors = {}
    names = {mavutil.mavlink.mavlink_map[mid].msgname: hz for mid, hz in DEFAULT_RATES_HZ.items()}
    for name, nominal_hz in names.items():
        times = [t for t in arrivals.get(name, []) if start_s <= t <= end_s]
        if nominal_hz < 1.0:
            continue
        if len(times) < 2:
            errors[name] = 1.0
            continue
        measured_hz = (len(times) - 1) / (times[-1] - times[0])
        errors[name] = abs(measured_hz / nominal_hz - 1.0)
    return errors


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """Measure telemetry rate error and setpoint latency over a loopback link."""
    window_s = 4.0 if quick else 15.0
    sim = Simulator(load_sim_config("iris"), seed=0)
    endpoint = MavlinkEndpoint(sim, EndpointConfig(links=(LinkConfig("bench"),), speed=1.0))
    endpoint.start()
    client = _Client(endpoint.local_port)
    try:
        _wait(lambda: bool(client.arrivals.get("HEARTBEAT")), "the first HEARTBEAT")
        progress("[bench link] arming and taking off")
        if client.command(400, 1.0) != 0 or client.command(22) != 0:
            raise RuntimeError("bench_link: arm or takeoff refused")
        _wait(
            lambda: endpoint.state.mode == FlightMode.HOLD and -endpoint.state.pos_ned_m[2] > 2.3,
            "takeoff",
        )
        client.streaming.set()
        _wait(lambda: endpoint.stats.setpoints_accepted > 10, "the setpoint stream")
        if client.command(176, 1.0, 6.0, 0.0) != 0:
            raise RuntimeError("bench_link: OFFBOARD refused")
        progress(f"[bench link] streaming 50 Hz setpoints for {window_s:.0f} s")
        start_s, accepted0 = time.perf_counter(), endpoint.stats.setpoints_accepted
        time.sleep(window_s)
        end_s, accepted1 = time.perf_counter(), endpoint.stats.setpoints_accepted
        errors = _rate_errors(client.arrivals, start_s, end_s)
        trace = [a for a in endpoint.setpoint_trace() if start_s <= a.actuated_s <= end_s]
        latencies_ms = np.array(
            [
                (a.actuated_s - client.sent_s[a.time_boot_ms]) * 1e3
                for a in trace
                if a.time_boot_ms in client.sent_s
            ]
        )
    finally:
        client.close()
        endpoint.stop()
    worst = max(errors, key=errors.get)
    progress("[bench link] rate errors: " + ", ".join(f"{k} {v:.4f}" for k, v in errors.items()))
    progress(f"[bench link] {len(latencies_ms)} setpoints traced")
    if len(latencies_ms) == 0:
        raise RuntimeError("bench_link: no setpoint actuation traced")
    return {
        "telemetry_rate_error_max_fraction": float(errors[worst]),
        "setpoint_latency_median_ms": float(np.median(latencies_ms)),
        "setpoint_latency_p99_ms": float(np.percentile(latencies_ms, 99)),
        "setpoint_rate_hz": (accepted1 - accepted0) / (end_s - start_s),
    }
