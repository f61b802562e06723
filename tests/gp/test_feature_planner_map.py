"""The NMPC's feature vector comes from the same FeatureDefinition the dataset reads."""

import casadi as ca
import numpy as np
import pytest

from gp.features import feature_definition


def test_state_input_map_matches_the_logged_columns_order():
    fd = feature_definition("state_input", "first_order_lag", tau_s=0.4)
    model = fd.nominal()
    rng = np.random.default_rng(3)
    x, u = rng.normal(size=model.nx), rng.normal(size=model.nu)
    z = np.asarray(ca.DM(fd.planner_map(model)(ca.DM(x), ca.DM(u)))).ravel()
    # columns: vel (the lag model's velocity state x[3:6]), cmd_vel (u[:3]), cmd_yaw_rate (u[3])
    np.testing.assert_allclose(z, np.concatenate([x[3:6], u[:3], u[3:4]]))


def test_velocity_map_on_the_kinematic_model_is_the_command():
    fd = feature_definition("velocity", "kinematic_4dof", residual_dt_s=0.02)
    model = fd.nominal()
    u = np.array([0.3, -0.2, 0.1, 0.0])
    z = np.asarray(ca.DM(fd.planner_map(model)(ca.DM.zeros(4), ca.DM(u)))).ravel()
    np.testing.assert_allclose(z, u[:3])


@pytest.mark.parametrize(
    ("features", "nominal", "words"),
    [("history", "first_order_lag", "lagged"), ("state_input", "kinematic_4dof", "velocity state")],
)
def test_features_the_planner_cannot_build_are_refused_in_one_line(features, nominal, words):
    fd = feature_definition(features, nominal)
    with pytest.raises(ValueError, match=words) as info:
        fd.planner_map(fd.nominal())
    assert "\n" not in str(info.value)


def test_only_velocity_loop_models_carry_velocity():
    assert feature_definition("velocity", "first_order_lag").nominal().carries_velocity
    assert not feature_definition("velocity", "kinematic_4dof").nominal().carries_velocity


def test_position_state_map_takes_the_position_from_the_model_state():
    fd = feature_definition("position_state", "first_order_lag", tau_s=0.4)
    model = fd.nominal()
    x = np.arange(1.0, 8.0)  # pos (1, 2, 3), vel (4, 5, 6), yaw 7
    u = np.array([0.5, 0.6, 0.7, 0.8])
    z = np.asarray(ca.DM(fd.planner_map(model)(ca.DM(x), ca.DM(u)))).ravel()
    np.testing.assert_allclose(z, [1.0, 2.0, 4.0, 5.0, 6.0, 0.5, 0.6, 0.7, 0.8])


def test_velocity_history_lags_one_residual_interval():
    fd = feature_definition("velocity_history", "first_order_lag", residual_steps=5)
    assert fd.input_names[3:] == ("vel_n_mps[k-5]", "vel_e_mps[k-5]", "vel_d_mps[k-5]")
    assert fd.history_lag == 5 and fd.speed_columns == (0, 1, 2)
    assert fd.nominal().nx == 7 and fd.planner_model().nx == 10


def test_velocity_history_map_takes_the_previous_velocity_from_the_model_state():
    fd = feature_definition("velocity_history", "first_order_lag", residual_steps=5)
    model = fd.planner_model()
    x = np.arange(1.0, 11.0)  # pos (1, 2, 3), vel (4, 5, 6), yaw 7, previous vel (8, 9, 10)
    z = np.asarray(ca.DM(fd.planner_map(model)(ca.DM(x), ca.DM.zeros(4)))).ravel()
    np.testing.assert_allclose(z, [4.0, 5.0, 6.0, 8.0, 9.0, 10.0])


@pytest.mark.parametrize(
    ("features", "nominal", "steps", "words"),
    [
        ("history", "first_order_lag", 1, r"cmd_vel_n_mps\[k-1\]"),  # commands are not carried
        ("velocity_history", "kinematic_4dof", 5, "with a velocity state"),
    ],
)
def test_lags_the_planner_does_not_carry_are_still_refused(features, nominal, steps, words):
    fd = feature_definition(features, nominal, residual_steps=steps)
    with pytest.raises(ValueError, match=words) as info:
        fd.planner_map(fd.planner_model())
    assert "\n" not in str(info.value)


def test_velocity_history_on_a_model_without_velocity_is_not_advised_again():
    """Refused on kinematic_4dof, the fix must not be the same feature set on the same model."""
    fd = feature_definition("velocity_history", "kinematic_4dof", residual_steps=5)
    with pytest.raises(ValueError) as info:
        fd.planner_map(fd.planner_model())
    assert "kinematic_4dof has none: use the 'velocity' feature set" in str(info.value)
    assert "(first_order_lag) for 'velocity_history'" in str(info.value)


def test_velocity_change_is_the_velocity_minus_the_previous_velocity_state():
    fd = feature_definition("velocity_change", "first_order_lag", residual_steps=5)
    assert fd.input_names[3] == "vel_n_mps[k]-vel_n_mps[k-5]" and fd.max_lag == 5
    model = fd.planner_model()
    x = np.arange(1.0, 11.0)  # pos (1, 2, 3), vel (4, 5, 6), yaw 7, previous vel (8, 9, 10)
    z = np.asarray(ca.DM(fd.planner_map(model)(ca.DM(x), ca.DM.zeros(4)))).ravel()
    np.testing.assert_allclose(z, [4.0, 5.0, 6.0, -4.0, -4.0, -4.0])
