"""Ctrl-C during `make demo`'s first flight: the vehicle lands, every process the demo started
is stopped, and the demo exits 130 with one line (it said 'demo: error: the nominal flight did
not complete: interrupted by Ctrl-C' and exited 1, as for a failed flight)."""

from __future__ import annotations

import pytest

from tests.scripts.test_ctrl_c_one_line import run_and_interrupt


@pytest.mark.slow
def test_ctrl_c_in_the_nominal_flight_exits_130_in_one_line(tmp_path):
    args = ["--out", str(tmp_path / "demo")]
    code, out, err = run_and_interrupt("scripts.demo", args, "offboard; following the reference")
    assert code == 130, err
    lines = err.strip().splitlines()
    assert "safe stop: landed and disarmed" in err and "Traceback" not in err
    assert lines[-1] == "demo: interrupted; the simulator was stopped", lines[-3:]
    assert out == ""
