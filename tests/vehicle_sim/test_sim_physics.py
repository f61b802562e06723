"""Built-in physics against closed-form results: free fall, torque-free rotation, ground, motors."""

from __future__ import annotations

import numpy as np
import pytest

from vehicle_sim import load_sim_config
from vehicle_sim import physics as ph
from vehicle_sim.builtin_plant import BuiltinPlant
from vehicle_sim.config import GRAVITY_MPS2

DT = 0.002
NO_NOISE = np.zeros((0, 3))


def plant(effects=None, preset="iris"):
    return BuiltinPlant(load_sim_config(preset, effects))


def run(p: BuiltinPlant, n_cmd, seconds: float, noise=NO_NOISE):
    ph.run_plant(
        round(seconds / DT),
        DT,
        p.x,
        np.asarray(n_cmd, float),
        p.pp,
        p.rp,
        p.spin,
        p.ep,
        noise,
        p.aux,
    )


def rotation(q):
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_free_fall_with_motors_off_matches_g():
    p = plant()
    p.x[ph.POS + 2] = -500.0
    p.x[ph.VEL : ph.VEL + 3] = (1.0, -2.0, 0.0)
    run(p, np.zeros(4), 3.0)
    assert p.x[ph.VEL + 2] == pytest.approx(GRAVITY_MPS2 * 3.0, rel=1e-9)
    assert p.x[ph.POS + 2] == pytest.approx(-500.0 + 0.5 * GRAVITY_MPS2 * 9.0, rel=1e-9)
    assert p.x[ph.POS] == pytest.approx(3.0) and p.x[ph.POS + 1] == pytest.approx(-6.0)
    np.testing.assert_allclose(p.aux[ph.AUX_ACC : ph.AUX_ACC + 3], (0, 0, GRAVITY_MPS2))


def test_torque_free_spinning_body_keeps_angular_momentum():
    """With motors off, L = R J w is constant in the world frame; RK4 at 2 ms keeps it to 1e-6."""
    p = plant()
    p.pp[ph.P_JX : ph.P_JZ + 1] = (0.029, 0.041, 0.055)  # asymmetric: a real tumbling test
    p.x[ph.POS + 2] = -1000.0
    p.x[ph.RATES : ph.RATES + 3] = (1.5, -0.8, 2.5)
    inertia = np.diag(p.pp[ph.P_JX : ph.P_JZ + 1])

    def momentum():
        return rotation(p.x[ph.QUAT : ph.QUAT + 4]) @ inertia @ p.x[ph.RATES : ph.RATES + 3]

    l0 = momentum()
    rates0 = p.x[ph.RATES : ph.RATES + 3].copy()
    run(p, np.zeros(4), 10.0)
    assert np.linalg.norm(momentum() - l0) / np.linalg.norm(l0) < 1e-6
    assert not np.allclose(p.x[ph.RATES : ph.RATES + 3], rates0, atol=0.1)  # it did tumble


def test_hover_command_balances_weight_and_ground_holds_a_resting_vehicle():
    p = plant()
    hover = np.sqrt(load_sim_config("iris").vehicle.hover_thrust_norm)
    run(p, np.full(4, 0.9 * hover), 1.0)  # below hover: rests, never sinks
    assert p.x[ph.POS + 2] == 0.0 and p.aux[ph.AUX_CONTACT] == 1.0
    np.testing.assert_allclose(p.aux[ph.AUX_ACC : ph.AUX_ACC + 3], 0.0)
    run(p, np.full(4, 1.05 * hover), 1.0)  # above hover: takes off
    assert p.x[ph.POS + 2] < -0.05 and p.aux[ph.AUX_CONTACT] == 0.0
    p.x[ph.MOTORS : ph.MOTORS + 4] = hover
    p.x[ph.VEL : ph.VEL + 3] = 0.0
    run(p, np.full(4, hover), 0.1)
    assert abs(p.aux[ph.AUX_ACC + 2]) < 1e-9 and abs(p.x[ph.VEL + 2]) < 1e-9
    run(p, np.zeros(4), 3.0)  # motors off: falls, lands, stays on the ground level
    assert p.x[ph.POS + 2] == 0.0 and np.allclose(p.x[ph.VEL : ph.VEL + 3], 0.0)


def test_motor_speed_follows_command_with_first_order_lag():
    p = plant()
    tau = load_sim_config("iris").vehicle.motor_time_constant_s
    p.x[ph.POS + 2] = -100.0
    run(p, np.full(4, 0.8), tau)
    assert p.x[ph.MOTORS] == pytest.approx(0.8 * (1 - np.exp(-1.0)), rel=1e-6)


def test_rotor_thrust_gives_roll_pitch_and_yaw_torque_with_the_right_sign():
    """Front-right rotor (1) alone: body rolls left (-x), pitches up (+y), yaws +z (ccw rotor)."""
    p = plant()
    p.x[ph.POS + 2] = -100.0
    p.x[ph.MOTORS] = 0.5
    run(p, np.array([0.5, 0.0, 0.0, 0.0]), DT)
    rates = p.x[ph.RATES : ph.RATES + 3]
    assert rates[0] < 0 and rates[1] > 0 and rates[2] > 0
