"""MAVProxy (headless, commands on stdin) connects, arms and takes off over loopback UDP."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from mavlink_test_client import free_udp_port, make_endpoint, wait_until

from vehicle_sim import FlightMode

MAVPROXY = Path(sys.executable).with_name("mavproxy.py")
MODULES = "link,signing,param,arm,mode,cmdlong,misc"


class MavproxyProcess:
    """MAVProxy listening on a UDP port, its output collected by a reader thread."""

    def __init__(self, port: int, workdir: Path) -> None:
        self.lines: list[str] = []
        self.proc = subprocess.Popen(
            [
                sys.executable,
                str(MAVPROXY),
                "--master",
                f"udpin:127.0.0.1:{port}",
                "--no-state",
                "--default-modules",
                MODULES,
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            cwd=workdir,
            env={**os.environ, "HOME": str(workdir)},
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append(line.rstrip())

    def said(self, text: str) -> bool:
        return any(text in line for line in list(self.lines))

    def send(self, command: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()

    def close(self) -> int | None:
        """SIGTERM (MAVProxy's quit signal) and end of input; kill if it does not exit."""
        self.proc.send_signal(signal.SIGTERM)
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        try:
            return self.proc.wait(10.0)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5.0)
            return None


@pytest.mark.slow
@pytest.mark.skipif(not MAVPROXY.exists(), reason="MAVProxy is not installed (dev extra)")
def test_mavproxy_connects_arms_and_takes_off(tmp_path):
    port = free_udp_port()
    endpoint = make_endpoint(speed=2.0, remote_port=port).start()
    mavproxy = MavproxyProcess(port, tmp_path)
    try:
        wait_until(lambda: mavproxy.said("online system 1"), 30.0, "MAVProxy to see the vehicle")
        wait_until(lambda: mavproxy.said("Received"), 15.0, "MAVProxy to fetch the parameters")

        mavproxy.send("arm throttle")
        wait_until(lambda: endpoint.state.armed, 10.0, "arming from MAVProxy")
        wait_until(lambda: mavproxy.said("COMPONENT_ARM_DISARM: ACCEPTED"), 5.0, "arm ACK")

        mavproxy.send("long NAV_TAKEOFF 0 0 0 0 0 0 2.5")
        wait_until(lambda: -endpoint.state.pos_ned_m[2] > 1.0, 10.0, "the vehicle to climb")
        wait_until(
            lambda: endpoint.state.mode == FlightMode.HOLD and -endpoint.state.pos_ned_m[2] > 2.3,
            15.0,
            "takeoff to finish",
        )
        assert mavproxy.said("NAV_TAKEOFF: ACCEPTED")
        wait_until(lambda: mavproxy.said("Takeoff complete"), 5.0, "STATUSTEXT in MAVProxy")
        assert endpoint.state.armed
    finally:
        mavproxy.close()
        endpoint.stop()
