"""Identifying the velocity loop's lag from logs: the time constants come back from data made
by a lag with randomly drawn (seeded) time constants the identification never sees."""

import numpy as np
import pytest

from flightlog.schema import FlightLogRecorder
from gp.errors import DatasetError
from gp.lag_identification import identify_velocity_lag
from gp.training import TrainingConfig, train_residual_model


def lag_log(
    tau_s, tau_d_s, seed=0, n_rows=1500, dt_s=0.02, noise_mps=0.002, vertical=True, horizontal=True
):
    """A log of a vehicle whose velocity follows piecewise-constant commands with a first-order
    lag (exact discretisation), plus noise [m/s] added to the velocity at every step.

    ``vertical``: True for down commands up to 1 m/s, False for none, or a number: down commands
    up to that many m/s. ``horizontal``: False commands no north or east velocity."""
    rng = np.random.default_rng(seed)
    taus = np.array([tau_s, tau_s, tau_d_s])
    rec = FlightLogRecorder({"source": "synthetic-lag"})
    vel = np.zeros(3)
    cmd = np.zeros(3)
    for k in range(n_rows):
        if k % 60 == 0:
            down = 1.0 if vertical is True else float(vertical)
            north_east = 2.0 if horizontal else 0.0
            cmd = rng.uniform(-1.0, 1.0, 3) * np.array([north_east, north_east, down])
        rec.append(
            {
                "t_s": k * dt_s,
                "pos_n_m": 0.0,
                "pos_e_m": 0.0,
                "pos_d_m": -5.0,
                "vel_n_mps": vel[0],
                "vel_e_mps": vel[1],
                "vel_d_mps": vel[2],
                "q_w": 1.0,
                "q_x": 0.0,
                "q_y": 0.0,
                "q_z": 0.0,
                "cmd_vel_n_mps": cmd[0],
                "cmd_vel_e_mps": cmd[1],
                "cmd_vel_d_mps": cmd[2],
                "cmd_yaw_rate_radps": 0.0,
            }
        )
        vel = cmd + (vel - cmd) * np.exp(-dt_s / taus) + noise_mps * rng.normal(size=3)
    return rec.to_log()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_identifies_randomly_drawn_time_constants(seed):
    rng = np.random.default_rng(100 + seed)
    tau, tau_d = rng.uniform(0.15, 1.2), rng.uniform(0.1, 0.8)
    found = identify_velocity_lag([lag_log(tau, tau_d, seed=seed)])
    assert found.tau_s == pytest.approx(tau, rel=0.03)
    assert found.tau_d_s == pytest.approx(tau_d, rel=0.05)
    assert found.vertical_identified
    assert np.linalg.norm(found.lag_rmse_mps) < 0.2 * np.linalg.norm(found.kinematic_rmse_mps)


def test_one_step_errors_are_the_added_noise_with_the_lag_and_the_lag_itself_without():
    """With the identified lag the one-step prediction misses by the velocity noise added at
    each step (0.002 m/s) on every axis; the kinematic prediction v(k+1) = u(k) misses by the
    whole lag, the RMS of v(k+1) - u(k) over the log's rows."""
    log = lag_log(0.5, 0.3, seed=3)
    found = identify_velocity_lag([log])
    np.testing.assert_allclose(found.lag_rmse_mps, 0.002, rtol=0.1)
    vel = np.column_stack([log[f"vel_{a}_mps"] for a in "ned"])
    cmd = np.column_stack([log[f"cmd_vel_{a}_mps"] for a in "ned"])
    kinematic = np.sqrt(np.mean((vel[1:] - cmd[:-1]) ** 2, axis=0))
    np.testing.assert_allclose(found.kinematic_rmse_mps, kinematic, rtol=1e-9)
    assert found.n_rows == log.n_rows - 1


def test_a_weakly_excited_vertical_axis_is_identified():
    """Down commands of up to 0.1 m/s leave an RMS command gap above 0.02 m/s: enough to fit
    the vertical time constant, which differs from the horizontal one."""
    found = identify_velocity_lag([lag_log(0.5, 0.3, seed=3, vertical=0.1)])
    assert found.vertical_identified
    assert found.tau_d_s == pytest.approx(0.3, rel=0.05)


def test_unexcited_vertical_axis_takes_the_horizontal_time_constant():
    found = identify_velocity_lag([lag_log(0.6, 0.2, vertical=False)])
    assert not found.vertical_identified
    assert found.tau_d_s == found.tau_s == pytest.approx(0.6, rel=0.03)
    assert "copied" in found.describe()


def test_hover_only_logs_are_refused_in_one_line():
    log = lag_log(0.5, 0.5)
    still = {c: np.zeros(log.n_rows) for c in log.columns if "vel_" in c}
    with pytest.raises(DatasetError, match="never command a horizontal velocity change") as exc:
        identify_velocity_lag([type(log)({**log.columns, **still}, log.metadata)])
    assert "\n" not in str(exc.value)
    with pytest.raises(DatasetError, match="no usable rows"):
        identify_velocity_lag([log.slice(0, 2)])
    # climbs and descents only: the vertical axis moves, the horizontal lag is not in the log
    with pytest.raises(DatasetError, match="never command a horizontal velocity change"):
        identify_velocity_lag([lag_log(0.5, 0.5, horizontal=False)])


def test_training_against_first_order_lag_identifies_missing_time_constants():
    logs = [lag_log(0.7, 0.3, seed=s) for s in range(2)]
    messages = []
    result = train_residual_model(
        logs,
        TrainingConfig(features="state_input", nominal="first_order_lag", m=10, restarts=1),
        messages.append,
    )
    params = dict(result.model.features.nominal_params)
    assert params["tau_s"] == pytest.approx(0.7, rel=0.03)
    assert params["tau_d_s"] == pytest.approx(0.3, rel=0.05)
    assert result.model.training["identified_lag"]["tau_s"] == pytest.approx(params["tau_s"], 1e-3)
    assert any(m.startswith("identified velocity lag") for m in messages)
    # The identified lag leaves only the noise, so the GP has nothing left to take.
    assert max(result.metrics["nominal_rmse_mps"]) < 0.003


def test_given_time_constant_is_kept():
    result = train_residual_model(
        [lag_log(0.7, 0.3)],
        TrainingConfig(
            features="state_input",
            nominal="first_order_lag",
            nominal_params=(("tau_s", 0.3),),
            m=10,
            restarts=1,
        ),
    )
    assert dict(result.model.features.nominal_params) == {"tau_s": 0.3}
    assert "identified_lag" not in result.model.training
    assert max(result.metrics["nominal_rmse_mps"]) > 0.01


@pytest.mark.parametrize("seed", [0, 1])
def test_study_fit_keeps_the_structure_it_is_given(seed):
    """The study's later rounds fit the GP on the structure identified from the nominal
    flights: the time constants passed in are the model's, not those of the new logs."""
    from experiments.study.fitting import fit_residual

    rng = np.random.default_rng(seed)
    logged, given = rng.uniform(0.3, 1.0, 2), rng.uniform(0.3, 1.0, 2)
    logs = [lag_log(*logged, seed=seed + i, n_rows=600) for i in range(2)]
    structure = (("tau_d_s", float(given[1])), ("tau_s", float(given[0])))
    fit = fit_residual(
        logs, "random", 0.02, m=10, restarts=1, check_horizon_s=None, structure_params=structure
    )
    assert fit.model.features.nominal_params == structure
    assert fit.model.features.residual_steps == 5  # the NMPC's 0.1 s in the logs' 0.02 s steps
    identified = fit_residual(logs, "random", 0.02, m=10, restarts=1, check_horizon_s=None)
    assert dict(identified.model.features.nominal_params)["tau_s"] == pytest.approx(
        logged[0], rel=0.05
    )
