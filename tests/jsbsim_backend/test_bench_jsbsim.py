"""The JSBSim benchmark part runs and reports its figures under the stable names."""

import math

import pytest

from experiments.bench import jsbsim as bench_jsbsim


@pytest.mark.slow
def test_quick_run_reports_a_realtime_factor():
    messages = []
    figures = bench_jsbsim.run(progress=messages.append, quick=True)
    names = {"jsbsim_realtime_factor", "jsbsim_tracking_gain", "jsbsim_tracking_gain_min"}
    assert set(figures) == names
    assert all(math.isfinite(figures[n]) and figures[n] > 0.0 for n in names)
    assert figures["jsbsim_tracking_gain_min"] <= figures["jsbsim_tracking_gain"]
    assert any("real time" in m for m in messages)
