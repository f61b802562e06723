"""A `vehicle-sim` process starved of CPU catches up: its vehicle flies on through the stall.

The endpoint process is stopped (SIGSTOP) for longer than one pass of its loop while the client
keeps streaming setpoints, as a busy computer may starve it; afterwards its simulated clock must
be back on the wall clock (a frozen vehicle would lag by the stall) and the vehicle still in
OFFBOARD (the setpoints queued during the stall count: no false offboard loss).
"""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from mavlink_test_client import (
    HOLD_CUSTOM_MODE,
    MAV_RESULT_ACCEPTED,
    OFFBOARD_CUSTOM_MODE,
    Client,
    free_udp_port,
)

REPO = Path(__file__).resolve().parents[2]
CMD_ARM, CMD_TAKEOFF, CMD_SET_MODE = 400, 22, 176
STALL_S = 1.2  # over the old 0.25 s limit and over COM_OF_LOSS_T (1 s)
WINDOW_S = 0.6


def clock_offsets_s(client: Client, duration_s: float) -> list[float]:
    """Wall time minus the endpoint's simulated time (LOCAL_POSITION_NED.time_boot_ms) over
    ``duration_s``; the smallest is the least delayed sample."""
    offsets = []
    end = time.monotonic() + duration_s
    while time.monotonic() < end:
        msg = client.recv("LOCAL_POSITION_NED", 1.0)
        if msg is not None:
            offsets.append(time.monotonic() - 1e-3 * msg.time_boot_ms)
    return offsets


@pytest.mark.slow
def test_stopped_endpoint_catches_up_and_keeps_offboard():
    gcs_port = free_udp_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "scripts.vehicle_sim_cli", "--gcs-port", str(gcs_port),
         "--offboard-port", str(free_udp_port()), "--offboard-bind-port", "0",
         "--gcs-bind-port", "0"],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )  # fmt: skip
    client = Client(url=f"udpin:127.0.0.1:{gcs_port}")
    try:
        client.hello(60.0)
        assert client.command(CMD_ARM, 1).result == MAV_RESULT_ACCEPTED
        assert client.command(CMD_TAKEOFF, *[math.nan] * 7).result == MAV_RESULT_ACCEPTED
        assert client.recv("HEARTBEAT", 20.0, lambda m: m.custom_mode == HOLD_CUSTOM_MODE)
        client.start_stream((1.0, 0.0, 0.0))
        time.sleep(0.5)
        assert client.command(CMD_SET_MODE, 129, 6, 0).result == MAV_RESULT_ACCEPTED
        time.sleep(1.0)
        before = min(clock_offsets_s(client, WINDOW_S))

        os.kill(proc.pid, signal.SIGSTOP)
        time.sleep(STALL_S)
        os.kill(proc.pid, signal.SIGCONT)
        time.sleep(0.5)
        client.forget()
        after = min(clock_offsets_s(client, WINDOW_S))

        assert after - before < 0.5 * STALL_S, f"simulated clock {after - before:.2f} s behind"
        heartbeat = client.recv("HEARTBEAT", 3.0, lambda m: m.get_srcSystem() == 1)
        assert heartbeat is not None and heartbeat.custom_mode == OFFBOARD_CUSTOM_MODE
    finally:
        client.close()
        proc.send_signal(signal.SIGCONT)
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=15.0)
    assert proc.returncode == 0, out
    counts = re.search(r"caught up (\d+) ms after stalls, dropped time (\d+) times", out)
    assert counts is not None and int(counts[1]) >= 500 * STALL_S and int(counts[2]) == 0, out
