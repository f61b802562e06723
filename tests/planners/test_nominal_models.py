"""Nominal models: the CasADi and NumPy forms agree, and RK4 matches closed-form solutions."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from planners.nominal_models import first_order_lag, kinematic_4dof, make_model, unicycle


def test_kinematic_model_moves_at_commanded_velocity():
    model = kinematic_4dof()
    x0 = np.array([1.0, 2.0, -3.0, 0.1])
    u = np.array([0.5, -1.0, 0.2, 0.3])
    np.testing.assert_allclose(model.step_np(x0, u, 0.4), x0 + 0.4 * u, atol=1e-12)
    np.testing.assert_allclose(model.predicted_velocity_np(x0, u, 0.05), u[:3])


def test_lag_model_matches_exponential_solution():
    tau_s, dt_s = 0.3, 0.05
    model = first_order_lag(tau_s)
    x = np.zeros(7)
    u = np.array([2.0, -1.0, 0.5, 0.0])
    for _ in range(20):
        x = model.step_np(x, u, dt_s)
    t_s = 20 * dt_s
    expected_vel = u[:3] * (1 - np.exp(-t_s / tau_s))
    expected_pos = u[:3] * (t_s - tau_s * (1 - np.exp(-t_s / tau_s)))
    np.testing.assert_allclose(x[3:6], expected_vel, rtol=1e-5)
    np.testing.assert_allclose(x[:3], expected_pos, rtol=1e-4)


def test_unicycle_drives_a_circle():
    model = unicycle()
    x = np.zeros(3)
    speed_mps, turn_radps, n = 1.0, 0.5, 1000
    dt_s = 2 * np.pi / turn_radps / n
    for _ in range(n):
        x = model.step_np(x, np.array([speed_mps, turn_radps]), dt_s)
    np.testing.assert_allclose(x, [0.0, 0.0, 2 * np.pi], atol=1e-9)


def test_batch_numpy_equals_symbolic_and_residual_enters_through_b_z():
    model = first_order_lag(0.25)
    rng = np.random.default_rng(0)
    xs = rng.normal(size=(8, 7))
    us = rng.normal(size=(8, 4))
    batch = model.xdot_np(xs, us)
    for i in range(8):
        np.testing.assert_allclose(batch[i], np.asarray(model.f(xs[i], us[i])).ravel())
    residual = ca.DM([0.1, -0.2, 0.3])
    with_residual = np.asarray(model.xdot(ca.DM(xs[0]), ca.DM(us[0]), residual)).ravel()
    np.testing.assert_allclose(with_residual[3:6] - batch[0][3:6], [0.1, -0.2, 0.3])
    np.testing.assert_allclose(with_residual[:3], batch[0][:3])


def test_kinematic_residual_corrects_velocity_by_its_time_base():
    model = kinematic_4dof(residual_dt_s=0.05)
    xdot = np.asarray(model.xdot(ca.DM.zeros(4), ca.DM([1, 0, 0, 0]), ca.DM([2.0, 0, 0]))).ravel()
    np.testing.assert_allclose(xdot, [1.0 + 2.0 * 0.05, 0, 0, 0])


def test_bad_inputs_give_clear_errors():
    with pytest.raises(ValueError, match="expected x of shape \\(n, 7\\)"):
        first_order_lag().xdot_np(np.zeros(4), np.zeros(4))
    with pytest.raises(ValueError, match="tau_s must be > 0"):
        first_order_lag(0.0)
    # an infinite time constant or gain is no model (it passed, and fit-gp fitted on it)
    for model, param in (
        ("first_order_lag", "tau_s"),
        ("first_order_lag", "tau_d_s"),
        ("kinematic_4dof", "residual_dt_s"),
        ("px4_velocity_pi", "vel_p_xy"),
        ("px4_velocity_pi", "vel_i_z"),
    ):
        for bad in (math.inf, math.nan):
            with pytest.raises(ValueError, match=f"{model}: {param} must be .* finite, got"):
                make_model(model, **{param: bad})
    with pytest.raises(ValueError, match="unknown nominal model 'bicycle'; choose one of"):
        make_model("bicycle")
