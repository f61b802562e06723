"""Test helpers: a simulator behind an in-process endpoint, and a small pymavlink client."""

from __future__ import annotations

import os
import queue
import threading
import time
from collections.abc import Callable

os.environ["MAVLINK20"] = "1"

from pymavlink import mavutil  # noqa: E402

from tests.free_port import free_udp_port  # noqa: F401 (imported from here too)
from vehicle_sim import Simulator, load_sim_config  # noqa: E402
from vehicle_sim.mavlink import EndpointConfig, LinkConfig, MavlinkEndpoint  # noqa: E402
from vehicle_sim.mavlink.params import float_as_int32, int32_as_float  # noqa: E402

LOOPBACK = "127.0.0.1"
MAV_RESULT_ACCEPTED = 0
MAV_RESULT_TEMPORARILY_REJECTED = 1
MAV_RESULT_UNSUPPORTED = 3
OFFBOARD_CUSTOM_MODE = 393216
HOLD_CUSTOM_MODE = 50593792
LAND_CUSTOM_MODE = 100925440
MASK_VELOCITY_YAW_RATE = 1479


def make_endpoint(
    speed: float = 3.0,
    remote_port: int | None = None,
    signing_key: bytes | None = None,
    seed: int = 0,
) -> MavlinkEndpoint:
    """An iris simulator behind one loopback link (not started)."""
    remote = (LOOPBACK, remote_port) if remote_port is not None else None
    link = LinkConfig("api", remote=remote, signing_key=signing_key)
    return MavlinkEndpoint(
        Simulator(load_sim_config("iris"), seed=seed), EndpointConfig(links=(link,), speed=speed)
    )


def wait_until(predicate: Callable[[], bool], timeout_s: float, what: str) -> None:
    """Poll ``predicate`` until true; AssertionError naming ``what`` after ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


class Client:
    """A pymavlink GCS-like client: sends to an endpoint's ``port`` (udpout) or uses ``url``.

    A reader thread drains the socket continuously into a queue, so telemetry never fills the
    socket buffer while a test waits (the kernel would then drop the replies it waits for).
    """

    def __init__(
        self,
        port: int | None = None,
        source_system: int = 245,
        signing_key: bytes | None = None,
        url: str | None = None,
    ):
        self.conn = mavutil.mavlink_connection(
            url or f"udpout:{LOOPBACK}:{port}",
            source_system=source_system,
            source_component=190,
            dialect="common",
        )
        if signing_key is not None:
            self.conn.setup_signing(signing_key, sign_outgoing=True)
        self.source_system = source_system
        self.send_lock = threading.Lock()
        self._inbox: queue.Queue = queue.Queue()
        self._closed = threading.Event()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        self._streaming = threading.Event()
        self._stream_thread: threading.Thread | None = None

    def _read(self) -> None:
        while not self._closed.is_set():
            try:
                msg = self.conn.recv_match(blocking=True, timeout=0.05)
            except OSError:  # closed under us, or ICMP from a stopped endpoint
                continue
            if msg is not None:
                self._inbox.put(msg)

    @property
    def mav(self):
        return self.conn.mav

    def hello(self, timeout_s: float = 5.0):
        """Send a heartbeat (so the endpoint knows us) until its heartbeat arrives."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self.send_lock:
                self.mav.heartbeat_send(6, 8, 0, 0, 0)
            msg = self.recv("HEARTBEAT", 0.5, lambda m: m.get_srcSystem() == 1)
            if msg is not None:
                return msg
        raise AssertionError("no HEARTBEAT from the endpoint")

    def recv(self, type_: str, timeout_s: float, cond: Callable | None = None):
        """Next received message of a type satisfying ``cond`` (earlier ones are consumed),
        or None after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while True:
            remaining_s = deadline - time.monotonic()
            if remaining_s <= 0:
                return None
            try:
                msg = self._inbox.get(timeout=remaining_s)
            except queue.Empty:
                return None
            if msg.get_type() == type_ and (cond is None or cond(msg)):
                return msg

    def forget(self) -> None:
        """Drop every message received so far."""
        while not self._inbox.empty():
            self._inbox.get_nowait()

    def command(
        self,
        command: int,
        *params: float,
        target_system: int = 1,
        timeout_s: float = 3.0,
        use_int: bool = False,
    ):
        """Send a COMMAND_LONG (or COMMAND_INT) and return its ACK (None if none came)."""
        p = list(params) + [0.0] * (7 - len(params))
        self.forget()
        with self.send_lock:
            if use_int:
                self.mav.command_int_send(
                    target_system, 1, 0, command, 0, 0, *p[:4], int(p[4]), int(p[5]), p[6]
                )
            else:
                self.mav.command_long_send(target_system, 1, command, 0, *p)
        return self.recv(
            "COMMAND_ACK",
            timeout_s,
            lambda m: m.command == command and m.target_system == self.source_system,
        )

    def set_param(self, name: str, value: float):
        """PARAM_SET as REAL32; the PARAM_VALUE echo (None if none came)."""
        self.forget()
        with self.send_lock:
            self.mav.param_set_send(1, 1, name.encode(), value, 9)
        return self.recv("PARAM_VALUE", 3.0, lambda m: m.param_id == name)

    def set_int_param(self, name: str, value: int) -> int | None:
        """PARAM_SET as INT32, encoded bytewise as PX4 expects; the echoed integer value."""
        self.forget()
        with self.send_lock:
            self.mav.param_set_send(1, 1, name.encode(), int32_as_float(value), 6)
        echo = self.recv("PARAM_VALUE", 3.0, lambda m: m.param_id == name)
        return None if echo is None else float_as_int32(echo.param_value)

    def send_velocity(
        self,
        vel_ned_mps=(0.0, 0.0, 0.0),
        frame: int = 1,
        mask: int = MASK_VELOCITY_YAW_RATE,
        yaw_rate_radps: float = 0.0,
        time_boot_ms: int = 0,
        target_system: int = 1,
    ):
        with self.send_lock:
            self.mav.set_position_target_local_ned_send(
                time_boot_ms,
                target_system,
                1,
                frame,
                mask,
                0.0,
                0.0,
                0.0,
                *vel_ned_mps,
                0.0,
                0.0,
                0.0,
                0.0,
                yaw_rate_radps,
            )

    def start_stream(self, vel_ned_mps=(0.0, 0.0, 0.0), rate_hz: float = 20.0) -> None:
        """Stream a constant velocity setpoint from a thread until ``stop_stream``."""
        self._streaming.set()

        def run() -> None:
            while self._streaming.is_set():
                self.send_velocity(vel_ned_mps)
                time.sleep(1.0 / rate_hz)

        self._stream_thread = threading.Thread(target=run, daemon=True)
        self._stream_thread.start()

    def stop_stream(self) -> None:
        self._streaming.clear()
        if self._stream_thread is not None:
            self._stream_thread.join(2.0)

    def close(self) -> None:
        self.stop_stream()
        self._closed.set()
        self._reader.join(2.0)
        self.conn.close()
