"""Smoke test of the GP benchmark in quick mode (no timing assertions)."""

import math

import pytest

from experiments.bench.gp import run


@pytest.mark.slow
def test_quick_bench_returns_every_figure():
    figures = run(progress=lambda message: None, quick=True)
    for name in (
        "gp_fit_s",
        "gp_fit_rmse",
        "gp_sklearn_fit_s",
        "gp_sklearn_rmse",
        "gp_predict_us",
        "gp_predict_call_us",
        "gp_predict_ingraph_us",
        "gp_fit_peak_mib",
        "gp_fit_peak_mib_at_sklearn_n",
        "gp_sklearn_fit_peak_mib",
    ):
        assert math.isfinite(figures[name]) and figures[name] > 0, name
    assert figures["gp_fit_rmse"] < 0.05
    # on the same rows the exact GP holds n x n kernels, the sparse one n x m
    assert figures["gp_fit_peak_mib_at_sklearn_n"] < figures["gp_sklearn_fit_peak_mib"]
