"""`bench --only nmpc --quick`: issue 17's figures come out beside today's, finite where they
must be (the acados ones are NaN only when acados is not installed), with the planner's own
CPU time and the share of plans the operating system preempted."""

from __future__ import annotations

import math

import pytest

from experiments.bench import nmpc
from experiments.bench.acados_peer import acados_unavailable


@pytest.mark.slow
def test_quick_nmpc_part_reports_augmented_acados_and_model_ready_figures():
    figures = nmpc.run(progress=lambda message: None, quick=True)
    for name in (
        "nmpc_fast_median_ms",
        "nmpc_ipopt_median_ms",
        "nmpc_augmented_median_ms",
        "nmpc_augmented_p99_ms",
        "nmpc_augmented_ipopt_median_ms",
        "nmpc_augmented_ipopt_paced_median_ms",
        "nmpc_augmented_cpu_p99_ms",
        "nmpc_augmented_normal_priority_median_ms",
        "nmpc_augmented_normal_priority_p99_ms",
        "nmpc_augmented_paced_code_warm_median_ms",
        "nmpc_augmented_ipopt_over_fast_paced",
        "nmpc_augmented_ipopt_over_fast_back_to_back",
        "nmpc_model_ready_s",
    ):
        assert math.isfinite(figures[name]) and figures[name] > 0, name
    assert 0.0 <= figures["nmpc_augmented_preempted_fraction"] <= 1.0
    assert math.isfinite(figures["nmpc_model_ready_peak_mib"])
    assert figures["nmpc_model_ready_peak_mib"] >= 0.0
    for regime in nmpc.REGIME_SHAPES:  # each regime's learned model, batched vs symbolic
        prefix = f"nmpc_learned_{regime}"
        for name in ("median_ms", "p99_ms", "cpu_p99_ms", "symbolic_median_ms"):
            assert math.isfinite(figures[f"{prefix}_{name}"]) and figures[f"{prefix}_{name}"] > 0
        assert figures[f"{prefix}_cmd_diff_max_mps"] < 1e-5
    assert figures["nmpc_cmd_diff_median_mps"] < 1e-3
    acados = [
        figures[f"nmpc_acados_{n}"] for n in ("median_ms", "solve_median_ms", "paced_median_ms")
    ]
    if acados_unavailable():
        assert all(math.isnan(v) for v in acados)
    else:
        assert all(math.isfinite(v) and v > 0 for v in acados)
        assert figures["nmpc_acados_ok_fraction"] > 0.9
        assert figures["nmpc_acados_cmd_diff_median_mps"] < 1e-3


def test_what_c_code_prints_inside_goes_to_stderr_so_json_stays_clean(capfd):
    """acados prints its failed QPs with C's printf; `bench --json` must keep stdout JSON."""
    import ctypes

    from experiments.bench.acados_peer import c_stdout_to_stderr

    libc = ctypes.CDLL(None)
    print("before", flush=True)
    with c_stdout_to_stderr():
        libc.printf(b"SQP_RTI: QP solver returned error status 3\n")
    libc.fflush(None)
    print("after", flush=True)
    out, err = capfd.readouterr()
    assert out == "before\nafter\n"
    assert "QP solver returned error status 3" in err
