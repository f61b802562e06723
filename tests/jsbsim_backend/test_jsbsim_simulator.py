"""Our PX4-like flight control flies JSBSim's F450 through the simulator's in-process API."""

import numpy as np
import pytest

from tests.jsbsim_backend.jsbsim_helpers import airborne_sim, f450_config, stream
from vehicle_sim import (
    FlightMode,
    LandedState,
    SimConfigError,
    Simulator,
    VelocitySetpoint,
    load_sim_config,
)
from vehicle_sim.jsbsim_backend import JsbsimBackend

G_MPS2 = 9.80665


def test_takes_off_hovers_lands_and_disarms():
    config = f450_config()
    sim = Simulator(config, backend="jsbsim")
    assert isinstance(sim._plant, JsbsimBackend)
    assert sim.state.landed_state is LandedState.ON_GROUND
    assert sim.arm().accepted
    assert sim.takeoff(3.0).accepted
    assert sim.step(1.0).landed_state is LandedState.TAKEOFF
    s = sim.step(9.0)
    assert s.mode is FlightMode.HOLD
    assert s.pos_ned_m[2] == pytest.approx(-3.0, abs=0.1)
    np.testing.assert_allclose(s.vel_ned_mps, 0.0, atol=0.05)
    np.testing.assert_allclose(s.pos_ned_m[:2], 0.0, atol=0.05)
    assert s.thrust_n == pytest.approx(config.mass_kg * G_MPS2, rel=0.02)
    assert sim.land().accepted
    s = sim.step(6.0)
    assert s.landed_state is LandedState.ON_GROUND
    assert 0.0 <= s.pos_ned_m[2] < 0.01
    s = sim.step(3.0)
    assert not s.armed
    texts = [text for _, text in sim.drain_events()]
    assert "Landing detected" in texts and "Disarmed after landing" in texts


def test_velocity_step_is_tracked_at_constant_altitude():
    sim = airborne_sim("jsbsim")
    alt_m = -sim.state.pos_ned_m[2]
    states = stream(sim, (2.0, 0.0, 0.0), 8.0)
    vel = np.array([s.vel_ned_mps for s in states])
    assert vel[20, 0] > 1.0  # 1 s in
    assert vel[-1, 0] == pytest.approx(2.0, abs=0.15)
    assert np.max(vel[:, 0]) < 2.5
    assert np.max(np.abs(vel[:, 1])) < 0.05
    assert np.max(np.abs([-s.pos_ned_m[2] - alt_m for s in states])) < 0.15
    # tilting forward to accelerate north: nose down (negative pitch) early in the step
    w, x, y, z = states[10].q_wxyz
    assert np.arcsin(2 * (w * y - z * x)) < -0.05


def test_log_rows_carry_engine_thrust_and_measured_acceleration():
    sim = airborne_sim("jsbsim")
    rows = []
    for _ in range(20):
        stream(sim, (0.0, 1.0, 0.0), 0.05)
        rows.append(sim.log_row(None))
    backend_state = sim._plant.plant.state()
    assert rows[-1]["thrust_n"] == pytest.approx(backend_state.thrust_n)
    assert rows[-1]["acc_e_mps2"] == pytest.approx(backend_state.acc_ned_mps2[1])
    vel_e = np.array([r["vel_e_mps"] for r in rows])
    acc_e = np.array([r["acc_e_mps2"] for r in rows])
    assert np.mean(acc_e) == pytest.approx((vel_e[-1] - vel_e[0]) / 0.95, abs=0.3)


def test_same_preset_flies_alike_on_both_backends():
    """The preset "f450" claims to be JSBSim's F450; a velocity step shows it roughly is."""
    vel = {}
    for backend in ("builtin", "jsbsim"):
        sim = airborne_sim(backend)
        vel[backend] = np.array([s.vel_ned_mps for s in stream(sim, (0.0, -2.0, 0.0), 4.0)])
    assert np.max(np.abs(vel["jsbsim"] - vel["builtin"])) < 0.15


def test_refuses_effects_other_vehicles_and_unknown_backends():
    with pytest.raises(SimConfigError, match="effects.rotor_drag"):
        Simulator(f450_config().with_effects({"rotor_drag": {}}), backend="jsbsim")
    with pytest.raises(SimConfigError, match="preset f450"):
        Simulator(load_sim_config("iris"), backend="jsbsim")
    with pytest.raises(ValueError, match="choose one of builtin, jsbsim"):
        Simulator(f450_config(), backend="xplane")


def test_yaw_rate_turns_clockwise_and_body_velocity_follows_the_nose():
    sim = airborne_sim("jsbsim")
    for _ in range(40):  # 2 s at +0.8 rad/s: nose from north towards east
        sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0), yaw_rate_radps=0.8))
        s = sim.step(0.05)
    assert 0.8 < s.yaw_rad < 2.0
    for _ in range(60):
        sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0), yaw_rad=np.pi / 2))
        s = sim.step(0.05)
    assert s.yaw_rad == pytest.approx(np.pi / 2, abs=0.05)
    for _ in range(60):
        sim.set_velocity_setpoint(VelocitySetpoint((1.0, 0.0, 0.0), frame="body"))
        s = sim.step(0.05)
    assert s.vel_ned_mps[1] == pytest.approx(1.0, abs=0.15)
    assert abs(s.vel_ned_mps[0]) < 0.15


@pytest.mark.usefixtures("flight_control_compiled")
def test_a_whole_flight_prints_nothing(capfd):
    sim = airborne_sim("jsbsim")
    stream(sim, (1.0, 1.0, -0.5), 1.0)
    out, err = capfd.readouterr()
    assert (out, err) == ("", "")


def test_same_calls_give_the_same_numbers():
    finals = []
    for _ in range(2):
        sim = Simulator(f450_config(), backend="jsbsim")
        sim.arm()
        sim.takeoff(2.0)
        finals.append(sim.step(3.0))
    for name in ("pos_ned_m", "vel_ned_mps", "q_wxyz", "acc_ned_mps2"):
        np.testing.assert_array_equal(getattr(finals[0], name), getattr(finals[1], name))
    assert finals[0].pos_ned_m[2] < -1.5
