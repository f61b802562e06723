"""The extended config carries fitted flight_control gains, horizontal and vertical, into
[px4_params], where the simulator's config loader reads them back."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.extend_config import write_extended_config
from vehicle_sim import load_sim_config


def test_fitted_velocity_gains_round_trip_through_the_extended_config(tmp_path):
    rng = np.random.default_rng(8)
    gains = {
        "MPC_XY_VEL_P_ACC": float(rng.uniform(1.3, 4.0)),
        "MPC_XY_VEL_I_ACC": float(rng.uniform(0.5, 3.0)),
        "MPC_Z_VEL_P_ACC": float(rng.uniform(2.5, 10.0)),
        "MPC_Z_VEL_I_ACC": float(rng.uniform(0.3, 2.8)),
    }
    drag = {"c_n_per_mps2": [float(v) for v in rng.uniform(0.01, 0.1, 3)]}
    path = write_extended_config(
        "iris", {"flight_control": gains, "body_drag": drag}, tmp_path / "extended.toml"
    )
    config = load_sim_config(str(path))
    params = dict(config.px4_params)
    for name, value in gains.items():
        assert params[name] == pytest.approx(value)
    (effect,) = [e for e in config.effects if e.name == "body_drag"]
    assert list(effect.c_n_per_mps2) == pytest.approx(drag["c_n_per_mps2"])
