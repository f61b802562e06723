"""A log's velocity-loop gains under their pre-v1.11 names are scaled by MPC_THR_HOVER, else by
the hover thrust its flight shows, and the source is named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flightlog.schema import FlightLog
from flightlog.ulog import read_ulog
from flightlog.velocity_loop_gains import (
    GRAVITY_MPS2,
    OLD_TO_ACC,
    estimated_hover_thrust,
    velocity_loop_gains,
)

POSCTL = Path(__file__).resolve().parents[1] / "fixtures" / "ulog" / "quad_posctl_v1_15.ulg"


def test_without_mpc_thr_hover_old_gains_are_scaled_by_the_measured_hover_thrust() -> None:
    """The real POSCTL flight (produced thrust from actuator_motors) with its gains under their
    old names and no MPC_THR_HOVER: the scale is its median produced thrust in hover."""
    log = read_ulog(POSCTL)
    params = dict(log.metadata["px4_params"])
    del params["MPC_THR_HOVER"]
    params |= {old: params.pop(new) * 0.5 / GRAVITY_MPS2 for old, new in OLD_TO_ACC.items()}
    logged = velocity_loop_gains(FlightLog(log.columns, {**log.metadata, "px4_params": params}))
    hover = estimated_hover_thrust(log)
    assert hover is not None and 0.2 < hover < 0.8
    assert logged.gains is not None
    flown = log.metadata["px4_params"]["MPC_XY_VEL_P_ACC"]
    assert logged.gains["vel_p_xy"] == pytest.approx(flown * 0.5 / hover, rel=1e-9)
    assert logged.source.endswith(
        f"x g / hover thrust {hover:.3f} (median produced thrust in hover)"
    )


def test_the_hover_thrust_is_the_median_over_the_slow_airborne_rows_only() -> None:
    """A drawn hover thrust on the slow airborne rows (a tenth of them spikes to full thrust),
    more rows flown fast at more thrust and more rows landed at idle, shuffled: the estimate is
    the hover thrust, which neither the fast rows, the landed ones nor the spikes move."""
    rng = np.random.default_rng(29)
    hover = rng.uniform(0.3, 0.7)
    n_hover, n_fast, n_landed = 60, 80, 70
    hovering = hover + rng.normal(0.0, 0.002, n_hover)
    hovering[rng.choice(n_hover, n_hover // 10, replace=False)] = 1.0
    thrust = np.r_[hovering, rng.uniform(1.2, 1.5, n_fast) * hover, np.full(n_landed, 0.05)]
    speed = np.r_[
        rng.uniform(0.0, 0.25, n_hover), rng.uniform(1.0, 5.0, n_fast), np.zeros(n_landed)
    ]
    heading = rng.uniform(-np.pi, np.pi, speed.size)
    landed = np.r_[np.zeros(n_hover + n_fast), np.ones(n_landed)]
    order = rng.permutation(speed.size)
    cols = {
        "t_s": 0.1 * np.arange(speed.size),
        "vel_n_mps": (speed * np.cos(heading))[order],
        "vel_e_mps": (speed * np.sin(heading))[order],
        "vel_d_mps": np.zeros(speed.size),
        "thrust_norm": thrust[order],
        "landed": landed[order],
    }
    log = FlightLog(cols, {"thrust_source": {"kind": "produced"}})
    assert estimated_hover_thrust(log) == pytest.approx(hover, abs=0.002)


def test_a_hover_thrust_of_zero_scales_no_gain() -> None:
    """MPC_THR_HOVER 0 (no hover thrust: PX4's range is 0.1-0.8) is passed over for the
    flight's, and a flight whose produced thrust in hover is 0 (motors idle on the ground in a
    log that does not say it landed) gives none: old gains were divided by 0
    (ZeroDivisionError out of fit-gp and config-from-log)."""
    log = read_ulog(POSCTL)
    params = dict(log.metadata["px4_params"])
    params |= {old: params.pop(new) * 0.5 / GRAVITY_MPS2 for old, new in OLD_TO_ACC.items()}
    params["MPC_THR_HOVER"] = 0.0
    logged = velocity_loop_gains(FlightLog(log.columns, {**log.metadata, "px4_params": params}))
    assert logged.gains is not None
    assert logged.source.endswith("(median produced thrust in hover)")
    idle = {**log.columns, "thrust_norm": np.zeros(log.n_rows)}
    idle_log = FlightLog(idle, {**log.metadata, "px4_params": params})
    assert estimated_hover_thrust(idle_log) is None
    refused = velocity_loop_gains(idle_log)
    assert refused.gains is None
    assert "no MPC_THR_HOVER parameter in (0, 1], no produced thrust while hovering" in (
        refused.source
    )
