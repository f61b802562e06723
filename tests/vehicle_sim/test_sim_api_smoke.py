"""Smoke test of the in-process contract: build, arm, take off, fly offboard, log, land."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from flightlog.schema import FlightLogRecorder, read_flight_log, write_flight_log
from tests.vehicle_sim.sim_flying import fly
from vehicle_sim import (
    CheckedSetpoint,
    CommandResult,
    FlightMode,
    LandedState,
    Simulator,
    VelocitySetpoint,
    load_sim_config,
)


def test_full_flight_through_the_public_api(tmp_path):
    sim = Simulator(load_sim_config("iris"), seed=1)
    s = sim.state
    assert (s.armed, s.mode, s.landed_state) == (False, FlightMode.HOLD, LandedState.ON_GROUND)
    assert np.allclose(s.pos_ned_m, 0.0) and sim.physics_dt_s == 0.002
    assert sim.config.preset_name == "iris" and sim.config.mass_kg == 1.5

    assert sim.arm() == CommandResult(True, "accepted", "")
    assert sim.takeoff().accepted
    assert sim.step(1.0).landed_state is LandedState.TAKEOFF
    sim.step(9.0)
    assert sim.state.mode is FlightMode.HOLD
    assert abs(-sim.state.pos_ned_m[2] - 2.5) < 0.05

    rec = FlightLogRecorder(sim.log_metadata())
    cmd = VelocitySetpoint((1.0, 0.0, 0.0), frame="body")
    sim.set_velocity_setpoint(cmd)
    assert sim.set_mode(FlightMode.OFFBOARD).accepted
    for _ in range(60):
        sim.set_velocity_setpoint(cmd)
        sim.step(0.05)
        rec.append(sim.log_row(cmd))
    assert sim.state.vel_ned_mps[0] > 0.9
    assert rec.to_log()["cmd_vel_n_mps"][-1] == 1.0

    assert sim.land().accepted
    sim.step(8.0)
    assert sim.state.armed is False and sim.state.landed_state is LandedState.ON_GROUND
    events = [text for _, text in sim.drain_events()]
    assert "Disarmed after landing" in events and sim.drain_events() == []

    path = write_flight_log(tmp_path / "truth.csv", rec.to_log())
    log = read_flight_log(path)
    assert log.metadata["vehicle"] == "iris" and log.n_rows == 60
    assert np.all(log["thrust_n"] > 0) and set(log["mode"]) == {"OFFBOARD"}


def test_params_are_px4_named_and_validated():
    sim = Simulator(load_sim_config("iris"))
    names = sim.param_names()
    assert names == tuple(sorted(names)) and "MPC_XY_VEL_MAX" in names
    assert sim.get_param("MIS_TAKEOFF_ALT") == 2.5 and sim.get_param("COM_OF_LOSS_T") == 1.0
    sim.set_param("MIS_TAKEOFF_ALT", 4.0)
    assert sim.get_param("MIS_TAKEOFF_ALT") == 4.0
    sim.set_param("MC_PITCH_P", 3.0)  # a gain reaches the flight control
    assert sim.arm().accepted and sim.takeoff().accepted
    sim.step(6.0)
    assert -sim.state.pos_ned_m[2] == pytest.approx(4.0, abs=0.15)
    for bad in (("NOPE", 1.0), ("MPC_XY_VEL_MAX", float("nan"))):
        try:
            sim.set_param(*bad)
        except ValueError as exc:
            assert bad[0] in str(exc)
        else:
            raise AssertionError(f"{bad} accepted")


def test_bad_setpoints_are_rejected_without_effect(iris_hover):
    sim = iris_hover
    before = sim.log_row(None)["cmd_vel_n_mps"]
    for bad in (
        VelocitySetpoint((float("nan"), 0.0, 0.0)),
        VelocitySetpoint((1e6, 0.0, 0.0)),
        VelocitySetpoint((0.0, 0.0, 0.0), yaw_rate_radps=float("inf")),
        VelocitySetpoint((0.0, 0.0, 0.0), frame="enu"),  # type: ignore[arg-type]
    ):
        with pytest.raises(ValueError, match="setpoint"):
            sim.set_velocity_setpoint(bad)
    sim.step(0.5)
    assert sim.log_row(None)["cmd_vel_n_mps"] == before
    fly(sim, (0.0, 0.0, 0.0), 0.2)
    assert sim.state.mode is FlightMode.OFFBOARD


def test_random_command_sequences_never_break_the_vehicle():
    """Seeded fuzz: any order of commands and setpoints keeps the state finite, above ground."""
    rng = np.random.default_rng(0)
    effects = {"rotor_drag": {}, "gusts": {}, "payload": {}, "command_delay": {}}
    for trial in range(12):
        sim = Simulator(load_sim_config("iris", effects if trial % 2 else None), seed=trial)
        for _ in range(120):
            r = rng.integers(0, 10)
            if r == 0:
                sim.arm(force=bool(rng.integers(0, 2)))
            elif r == 1:
                sim.takeoff(float(rng.uniform(0.5, 10.0)))
            elif r == 2:
                sim.land()
            elif r == 3:
                sim.set_mode(list(FlightMode)[rng.integers(0, len(FlightMode))])
            elif r == 4:
                sim.disarm(force=rng.random() < 0.2)
            else:
                vel = tuple(float(v) for v in rng.uniform(-15.0, 15.0, 3))
                frame = "ned" if rng.random() < 0.5 else "body"
                yaw_rate = float(rng.uniform(-3.0, 3.0))
                sim.set_velocity_setpoint(VelocitySetpoint(vel, yaw_rate, frame=frame))
            s = sim.step(float(rng.uniform(0.0, 0.5)))
            values = np.concatenate([s.pos_ned_m, s.vel_ned_mps, s.acc_ned_mps2, s.q_wxyz])
            assert np.all(np.isfinite(values)) and s.pos_ned_m[2] <= 0.0
            assert abs(np.linalg.norm(s.q_wxyz) - 1.0) < 1e-9
            assert all(np.isfinite(v) for v in sim.log_row(None).values() if not isinstance(v, str))


def test_a_checked_setpoint_is_validated_when_built_and_flies_as_the_plain_one(iris_hover):
    for bad in ((float("nan"), 0.0, 0.0), (1e6, 0.0, 0.0), (0.0, 0.0)):
        with pytest.raises(ValueError, match="setpoint"):
            CheckedSetpoint(bad)
    checked = CheckedSetpoint(np.array([1.0, -0.5, 0.2]), np.float32(0.25), frame="body")
    assert checked.vel_mps == (1.0, -0.5, 0.2) and type(checked.vel_mps[0]) is float
    assert type(checked.yaw_rate_radps) is float
    plain = VelocitySetpoint((1.0, -0.5, 0.2), 0.25, frame="body")
    states = []
    for sp in (checked, plain):
        sim = copy.deepcopy(iris_hover)
        for _ in range(5):
            sim.set_velocity_setpoint(sp)
            sim.step(0.05)
        states.append(np.concatenate([sim.state.pos_ned_m, sim.state.vel_ned_mps]))
    assert np.array_equal(states[0], states[1])
