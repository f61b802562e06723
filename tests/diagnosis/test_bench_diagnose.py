"""`bench --only diagnose` in quick mode gives finite, positive figures (no timing limits)."""

from __future__ import annotations

import math

import pytest

from experiments.bench.diagnose import run
from scripts.bench import PARTS


@pytest.mark.slow(expected_s=80)
def test_quick_bench_gives_finite_positive_figures():
    figures = run(progress=lambda msg: None, quick=True)
    assert PARTS["diagnose"] == "experiments.bench.diagnose"
    expected = {"diagnose_5min_s", "diagnose_speedup_vs_realtime", "diagnose_log_sim_s"}
    assert expected | {"diagnose_5min_cpu_s", "diagnose_5min_noisy_cpu_s"} <= set(figures)
    assert all(math.isfinite(v) and v > 0.0 for v in figures.values()), figures
    assert math.isclose(
        figures["diagnose_speedup_vs_realtime"],
        figures["diagnose_log_s"] / figures["diagnose_5min_s"],
    )
