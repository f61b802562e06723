"""The F450 plant behaves physically in our frames: gravity, thrust, torques, ground."""

import numpy as np
import pytest

from tests.jsbsim_backend.jsbsim_helpers import HOVER_CMD, airborne_hovering, fly
from vehicle_sim.jsbsim_backend import JsbsimF450Plant, PlantConfig
from vehicle_sim.jsbsim_backend.frames import quat_wxyz_from_dcm

G_MPS2 = 9.80665


def test_starts_at_rest_at_the_requested_height_and_heading():
    s = JsbsimF450Plant(PlantConfig(height_m=7.0, yaw_rad=np.pi / 2)).state()
    np.testing.assert_allclose(s.pos_ned_m, [0, 0, -7.0], atol=1e-6)
    np.testing.assert_allclose(s.vel_ned_mps, 0.0, atol=1e-9)
    np.testing.assert_allclose(s.q_wxyz, [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)], atol=1e-9)
    assert s.mass_kg == pytest.approx(1.4, rel=1e-6)
    assert not s.on_ground


def test_free_fall_with_motors_off_accelerates_down_at_g():
    """Early on, drag (JSBSim's C_D * S = 0.016 m^2) is negligible and gravity alone acts."""
    plant = JsbsimF450Plant(PlantConfig(height_m=10.0))
    fly(plant, np.zeros(4), 0.052)
    s = plant.state()
    assert s.acc_ned_mps2[2] == pytest.approx(G_MPS2, rel=1e-3)
    np.testing.assert_allclose(s.acc_ned_mps2[:2], 0.0, atol=1e-3)
    fly(plant, np.zeros(4), 0.3)
    s = plant.state()
    assert s.vel_ned_mps[2] == pytest.approx(G_MPS2 * s.t_s, rel=5e-3)  # drag: -0.3 %
    assert s.pos_ned_m[2] == pytest.approx(-10.0 + 0.5 * G_MPS2 * s.t_s**2, abs=0.005)
    assert s.thrust_n == 0.0


def test_acceleration_is_the_derivative_of_velocity():
    plant = airborne_hovering()
    fly(plant, np.full(4, 0.6), 0.2)
    vel_before = plant.state().vel_ned_mps
    plant.step(0.001)
    s = plant.state()
    np.testing.assert_allclose(s.acc_ned_mps2, (s.vel_ned_mps - vel_before) / 0.001, atol=1e-9)


def test_hover_command_balances_weight():
    plant = airborne_hovering()
    vel_start = plant.state().vel_ned_mps
    fly(plant, np.full(4, HOVER_CMD), 1.0)
    s = plant.state()
    assert abs(s.vel_ned_mps[2] - vel_start[2]) < 0.1
    assert abs(s.acc_ned_mps2[2]) < 0.15
    assert s.thrust_n == pytest.approx(s.mass_kg * G_MPS2, rel=0.015)
    np.testing.assert_allclose(s.rates_frd_radps, 0.0, atol=1e-6)


@pytest.mark.parametrize(("delta_cmd", "sign"), [(0.05, -1.0), (-0.05, 1.0)])
def test_more_throttle_climbs_less_descends(delta_cmd, sign):
    plant = airborne_hovering()
    vel_start_d = plant.state().vel_ned_mps[2]
    fly(plant, np.full(4, HOVER_CMD + delta_cmd), 1.0)
    s = plant.state()
    assert sign * (s.vel_ned_mps[2] - vel_start_d) > 0.8
    assert sign * s.acc_ned_mps2[2] > 0.5


# Our motor order (PX4 quad-X): 1 front-right CCW, 2 rear-left CCW, 3 front-left CW,
# 4 rear-right CW. Raising one motor rolls away from it, pitches away from it, and yaws the body
# against the propeller's spin (a CCW propeller yaws the body clockwise from above: +r).
@pytest.mark.parametrize(
    ("motor", "rate_signs"),
    [(1, (-1, 1, 1)), (2, (1, -1, 1)), (3, (1, 1, -1)), (4, (-1, -1, -1))],
)
def test_single_motor_turns_the_body_the_frd_way(motor, rate_signs):
    plant = airborne_hovering()
    cmds = np.full(4, HOVER_CMD)
    cmds[motor - 1] += 0.05
    fly(plant, cmds, 0.1)
    rates = plant.state().rates_frd_radps
    np.testing.assert_array_equal(np.sign(rates), rate_signs)
    assert np.min(np.abs(rates)) > 0.05


@pytest.mark.parametrize("yaw_rad", [0.0, np.pi / 2])
def test_rolling_right_accelerates_to_the_right(yaw_rad):
    """Left motors up: +roll, and the thrust tilts towards the body's right (east if facing north,
    south if facing east); the quaternion reports the tilt."""
    plant = airborne_hovering(yaw_rad=yaw_rad)
    fly(plant, np.array([-0.02, 0.02, 0.02, -0.02]) + HOVER_CMD, 0.3)
    s = plant.state()
    w, x, y, z = s.q_wxyz
    roll_rad = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    assert roll_rad > 0.1
    right_ned = np.array([-np.sin(yaw_rad), np.cos(yaw_rad)])
    assert s.vel_ned_mps[:2] @ right_ned > 0.1
    assert s.acc_ned_mps2[:2] @ right_ned > 1.0


def test_pitching_nose_up_accelerates_backwards():
    plant = airborne_hovering()
    fly(plant, np.array([0.02, -0.02, 0.02, -0.02]) + HOVER_CMD, 0.3)
    s = plant.state()
    assert s.rates_frd_radps[1] > 0.5
    assert s.vel_ned_mps[0] < -0.1
    assert s.acc_ned_mps2[0] < -1.0


def test_resting_on_the_ground_does_not_sink_or_slide():
    plant = JsbsimF450Plant()
    assert plant.state().on_ground
    fly(plant, np.zeros(4), 3.0)
    s = plant.state()
    assert s.on_ground
    assert 0.0 < s.pos_ned_m[2] < 0.005
    np.testing.assert_allclose(s.pos_ned_m[:2], 0.0, atol=0.002)
    np.testing.assert_allclose(s.vel_ned_mps, 0.0, atol=1e-4)


def test_dropped_from_a_metre_comes_to_rest_on_the_ground():
    plant = JsbsimF450Plant(PlantConfig(height_m=1.0))
    fly(plant, np.zeros(4), 3.0)
    s = plant.state()
    assert s.on_ground
    assert 0.0 < s.pos_ned_m[2] < 0.01
    assert abs(s.vel_ned_mps[2]) < 0.01


def test_takes_off_with_enough_throttle_and_lands_again():
    plant = JsbsimF450Plant()
    fly(plant, np.full(4, HOVER_CMD + 0.08), 1.0)
    s = plant.state()
    assert not s.on_ground
    assert s.pos_ned_m[2] < -0.3
    assert s.vel_ned_mps[2] < -0.5
    fly(plant, np.zeros(4), 3.0)
    s = plant.state()
    assert s.on_ground
    assert 0.0 < s.pos_ned_m[2] < 0.01


def test_step_splits_into_substeps_and_keeps_time():
    plant = JsbsimF450Plant(PlantConfig(height_m=5.0, max_substep_s=1e-3))
    for _ in range(8):
        plant.step(0.0025)
    assert plant.state().t_s == pytest.approx(0.02, abs=1e-12)


def test_same_commands_give_identical_states():
    states = []
    for _ in range(2):
        plant = airborne_hovering()
        fly(plant, np.array([0.5, 0.45, 0.42, 0.47]), 0.5)
        states.append(plant.state())
    for name in ("pos_ned_m", "vel_ned_mps", "q_wxyz", "rates_frd_radps"):
        np.testing.assert_array_equal(getattr(states[0], name), getattr(states[1], name))


@pytest.mark.parametrize("bad", [np.zeros(3), np.array([0.1, 0.2, np.nan, 0.3])])
def test_bad_motor_commands_are_refused(bad):
    with pytest.raises(ValueError, match="4 finite numbers"):
        JsbsimF450Plant().set_motor_commands(bad)


def test_bad_config_is_refused():
    with pytest.raises(ValueError, match="height_m"):
        PlantConfig(height_m=-1.0)
    with pytest.raises(ValueError, match="dt_s"):
        JsbsimF450Plant().step(0.0)


@pytest.mark.filterwarnings("ignore::PendingDeprecationWarning")  # JSBSim returns np.matrix
def test_attitude_agrees_with_jsbsim_own_rotation_matrix_while_tumbling():
    plant = airborne_hovering(height_m=200.0, yaw_rad=0.7)
    plant.set_motor_commands(np.array([0.3, 0.55, 0.5, 0.35]))
    for _ in range(60):
        plant.step(0.01)
        local_to_body = np.asarray(plant._fdm.get_propagate().get_Tl2b())
        q = plant.state().q_wxyz
        np.testing.assert_allclose(quat_wxyz_from_dcm(local_to_body.T), q, atol=1e-6)
