"""The JSBSim benchmark part runs and reports its figures under the stable names."""

import math
from pathlib import Path

import pytest

from experiments.bench import jsbsim as bench_jsbsim


@pytest.mark.slow(expected_s=95)
def test_quick_run_reports_a_realtime_factor(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the bench writes under out/bench/ where it runs
    messages = []
    figures = bench_jsbsim.run(progress=messages.append, quick=True)
    names = {"jsbsim_realtime_factor", "jsbsim_tracking_gain", "jsbsim_tracking_gain_min"}
    assert set(figures) == names
    assert all(math.isfinite(figures[n]) and figures[n] > 0.0 for n in names)
    assert figures["jsbsim_tracking_gain_min"] <= figures["jsbsim_tracking_gain"]
    assert any("real time" in m for m in messages)
    # the study behind the gains is there to read, where its progress said it went
    (wrote,) = [m.split("wrote ", 1)[1] for m in messages if m.startswith("wrote ")]
    assert Path(wrote).is_file() and Path(wrote).parent == bench_jsbsim.STUDY_OUT
    # no figure reads the trial-to-trial view: not flown, and the report says so
    assert "Not flown (`--trials 0`)" in Path(wrote).read_text()
    assert not any("trial-to-trial" in m for m in messages)
    assert not (Path(wrote).parent / "trials.png").exists()
