"""A deep copy of a simulator is independent of it and flies exactly as it would: the same gust
noise, setpoints delayed in flight and parameters, and nothing it does reaches the original."""

from __future__ import annotations

import copy

import numpy as np

from tests.vehicle_sim.sim_flying import fly, hovering
from vehicle_sim import VelocitySetpoint


def test_a_copy_flies_as_the_original_would_and_leaves_it_alone():
    effects = {"gusts": {"intensity_mps": 0.5}, "rotor_drag": {}, "command_delay": {"delay_s": 0.1}}
    sim = hovering(effects, seed=4)
    sim.set_velocity_setpoint(VelocitySetpoint((1.0, 0.0, 0.0)))  # still in flight when copied
    clone = copy.deepcopy(sim)
    assert clone.config is sim.config
    clone.set_param("MPC_XY_VEL_P_ACC", 2.5)
    assert sim.get_param("MPC_XY_VEL_P_ACC") != 2.5  # parameters are the copy's own
    clone.set_param("MPC_XY_VEL_P_ACC", sim.get_param("MPC_XY_VEL_P_ACC"))
    a = fly(sim, (1.0, -0.5, 0.0), 9.0)  # longer than a block of gust noise drawn ahead
    b = fly(clone, (1.0, -0.5, 0.0), 9.0)
    for sa, sb in zip(a, b, strict=True):
        assert np.array_equal(sa.vel_ned_mps, sb.vel_ned_mps)
        assert np.array_equal(sa.q_wxyz, sb.q_wxyz)
    fly(clone, (0.0, 2.0, 0.0), 1.0)
    assert sim.t_s == a[-1].t_s  # flying the copy moved the original not at all
    assert not np.array_equal(sim.state.vel_ned_mps, clone.state.vel_ned_mps)
