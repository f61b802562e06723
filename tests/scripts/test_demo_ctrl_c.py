"""Ctrl-C during `make demo`'s first flight: the vehicle lands, every process the demo started
is stopped, and the demo exits 130 with one line (it said 'demo: error: the nominal flight did
not complete: interrupted by Ctrl-C' and exited 1, as for a failed flight)."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_ctrl_c_in_the_nominal_flight_exits_130_in_one_line(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "scripts.demo", "--out", str(tmp_path / "demo")],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    try:
        for line in proc.stderr:
            if "offboard; following the reference" in line:
                break
        else:
            pytest.fail("the demo ended before its first flight followed the reference")
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)
    assert proc.returncode == 130, err
    lines = err.strip().splitlines()
    assert "safe stop: landed and disarmed" in err and "Traceback" not in err
    assert lines[-1] == "demo: interrupted; the simulator was stopped", lines[-3:]
    assert out == ""
