"""A physics backend plugs in through the PlantBackend protocol; parameters reach the control."""

from __future__ import annotations

import numpy as np
import pytest

from tests.vehicle_sim.sim_flying import fly, hovering
from vehicle_sim import FlightMode, Simulator, load_sim_config
from vehicle_sim import physics as ph
from vehicle_sim.builtin_plant import BuiltinPlant
from vehicle_sim.flight_control import control_step


class SteppedPlant:
    """A backend that runs control and physics one step at a time from Python, as an external
    plant (JSBSim) does: it must fly exactly like the fused built-in loop."""

    def __init__(self, config) -> None:
        self._inner = BuiltinPlant(config)
        self.x, self.aux = self._inner.x, self._inner.aux
        self.steps = 0

    def advance(self, n_steps, dt_s, sp, cs, cp, mix, noise) -> int:
        u = np.zeros(4)
        scratch = np.zeros((6, ph.N_DYN))
        contact0 = self.aux[ph.AUX_CONTACT]
        for k in range(n_steps):
            control_step(self.x, self.aux[ph.AUX_ACC : ph.AUX_ACC + 3], sp, cs, cp, mix, dt_s, u)
            n_cmd = np.sqrt(u)
            p = self._inner
            ph.plant_step(self.x, n_cmd, p.pp, p.rp, p.spin, p.ep, noise, k, dt_s, scratch, p.aux)
            self.aux[ph.AUX_CMD : ph.AUX_CMD + 4] = u
            self.steps += 1
            if self.aux[ph.AUX_CONTACT] != contact0:
                return k + 1
        return n_steps


def test_a_python_stepped_backend_flies_exactly_like_the_builtin_loop():
    config = load_sim_config("iris")
    runs = []
    for backend in ("builtin", SteppedPlant(config)):
        sim = Simulator(config, backend=backend)
        sim.arm()
        sim.takeoff()
        sim.step(6.0)
        runs.append(sim.state)
    assert runs[1].mode is FlightMode.HOLD and -runs[1].pos_ned_m[2] > 2.3
    np.testing.assert_allclose(runs[1].pos_ned_m, runs[0].pos_ned_m, atol=1e-9)
    np.testing.assert_allclose(runs[1].q_wxyz, runs[0].q_wxyz, atol=1e-9)


def test_unknown_backend_is_refused():
    with pytest.raises(ValueError, match="unknown backend 'xplane'; choose one of builtin"):
        Simulator(load_sim_config("iris"), backend="xplane")


def test_velocity_limit_parameters_apply_in_offboard():
    sim = hovering(settle_s=1.0)
    sim.set_param("MPC_XY_VEL_MAX", 3.0)
    sim.params.set("MPC_Z_VEL_MAX_UP", 1.0)  # through the parameter object too
    states = fly(sim, (6.0, 0.0, -4.0), 8.0)
    assert states[-1].vel_ned_mps[0] == pytest.approx(3.0, abs=0.1)
    assert states[-1].vel_ned_mps[2] == pytest.approx(-1.0, abs=0.05)
