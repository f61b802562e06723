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
