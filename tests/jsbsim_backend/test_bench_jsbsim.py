"""The JSBSim benchmark part runs and reports its figure under the stable name."""

import pytest

from experiments.bench import jsbsim as bench_jsbsim


@pytest.mark.slow
def test_quick_run_reports_a_realtime_factor():
    messages = []
    figures = bench_jsbsim.run(progress=messages.append, quick=True)
    assert set(figures) == {"jsbsim_realtime_factor"}
    assert figures["jsbsim_realtime_factor"] > 0.0
    assert any("real time" in m for m in messages)
