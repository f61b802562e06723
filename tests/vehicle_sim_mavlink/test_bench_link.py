"""scripts/bench_link: the figures exist, are finite and plausible (not a timing assertion)."""

from __future__ import annotations

import math

import pytest

from experiments.bench.link import run


@pytest.mark.slow
def test_bench_link_quick_reports_rates_and_latency():
    messages = []
    figures = run(progress=messages.append, quick=True)
    assert set(figures) == {
        "telemetry_rate_error_max_fraction",
        "setpoint_latency_median_ms",
        "setpoint_latency_p99_ms",
        "setpoint_rate_hz",
    }
    assert all(math.isfinite(v) and v >= 0.0 for v in figures.values())
    assert figures["setpoint_latency_median_ms"] <= figures["setpoint_latency_p99_ms"]
    assert figures["telemetry_rate_error_max_fraction"] < 1.0  # every stream arrived
    assert figures["setpoint_rate_hz"] > 10.0
    assert any("rate errors" in m for m in messages)
