"""The onboard log a simulator behind the MAVLink endpoint keeps: rows at its rate of simulated
time, with the acceleration and thrust MAVLink does not carry, and the command as received."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flightlog.schema import read_flight_log
from vehicle_sim import FlightMode, Simulator, VelocitySetpoint, load_sim_config
from vehicle_sim.onboard_log import OnboardLogger


def _offboard(logger: OnboardLogger) -> None:
    assert logger.arm().accepted
    assert logger.takeoff(2.0).accepted
    while logger.state.mode is not FlightMode.HOLD:
        logger.step(0.5)
    logger.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    logger.step(0.05)
    assert logger.set_mode(FlightMode.OFFBOARD).accepted


def test_rows_at_the_log_rate_with_measured_columns():
    sim = Simulator(load_sim_config("iris"), seed=0)
    logger = OnboardLogger(sim, rate_hz=25.0)
    t0 = sim.state.t_s
    for _ in range(400):  # 2 s in steps of 5 ms, as the endpoint steps it
        logger.step(0.005)
    log = logger.to_log()
    assert log.n_rows == pytest.approx((sim.state.t_s - t0) * 25.0, abs=1)
    assert np.allclose(np.diff(log["t_s"]), 0.04, atol=0.006)
    for column in ("acc_d_mps2", "thrust_n", "q_w", "vel_n_mps"):
        assert log.has(column)
    assert logger.physics_dt_s == sim.physics_dt_s  # everything else is the simulator's


def test_a_long_step_is_logged_at_the_log_rate_throughout():
    """The endpoint catching up after a stall (a busy computer) steps the simulator up to 2 s
    at once: the rows go on at the log's rate through it, as PX4's logger does, and the states
    are those of short steps. One row was written for the whole step, and a gap over 0.5 s
    ends the diagnosis's replay run there."""
    config = load_sim_config("iris")
    short, long = (OnboardLogger(Simulator(config, seed=4), rate_hz=50.0) for _ in range(2))
    for logger in (short, long):
        _offboard(logger)
        logger.set_velocity_setpoint(VelocitySetpoint((1.5, -0.5, 0.2)))
    for _ in range(500):
        short.step(short.physics_dt_s)
    long.step(500 * long.physics_dt_s)
    assert long.state.t_s == pytest.approx(short.state.t_s, abs=1e-9)
    a, b = short.to_log(), long.to_log()
    assert a.n_rows == b.n_rows
    assert np.max(np.diff(b["t_s"])) <= 0.02 + long.physics_dt_s + 1e-9  # one step's jitter
    np.testing.assert_allclose(b["t_s"], a["t_s"], atol=1e-9)
    np.testing.assert_allclose(b["vel_n_mps"], a["vel_n_mps"], atol=1e-9)


def test_the_logged_command_is_the_received_one_not_the_delayed_one():
    rng = np.random.default_rng(3)
    delay_s = float(rng.uniform(0.2, 0.4))
    speed = float(rng.uniform(1.0, 3.0))
    sim = Simulator(load_sim_config("iris", {"command_delay": {"delay_s": delay_s}}), seed=3)
    logger = OnboardLogger(sim, rate_hz=50.0)
    _offboard(logger)
    sent_at = logger.state.t_s
    for _ in range(40):
        logger.set_velocity_setpoint(VelocitySetpoint((speed, 0.0, 0.0)))
        logger.step(0.05)
    log = logger.to_log()
    after = log["t_s"] > sent_at + 0.03
    assert np.all(log["cmd_vel_n_mps"][after] == pytest.approx(speed))
    moving = log["t_s"][after & (log["vel_n_mps"] > 0.05)]
    assert moving[0] - sent_at > 0.8 * delay_s  # the vehicle still waited for it


def test_each_rows_command_is_the_one_flown_from_that_row_on():
    """Setpoints arriving off the logging grid, the simulator stepped in chunks of one to four
    physics steps as the endpoint steps it: every setpoint is logged at the instant it started
    to act, so a second simulator given row k's command from row k's time to row k+1's flies
    the logged states exactly (the replay's assumption, diagnosis.replay)."""
    rng = np.random.default_rng(11)
    config = load_sim_config("iris")
    sim = Simulator(config, seed=11)
    logger = OnboardLogger(sim, rate_hz=50.0)
    _offboard(logger)
    dt_s = sim.physics_dt_s
    start_row = logger.to_log().n_rows
    sent = []
    next_sp_s = logger.state.t_s
    for _ in range(1500):
        if logger.state.t_s >= next_sp_s:
            sp = VelocitySetpoint(tuple(rng.uniform(-2.0, 2.0, 3)), float(rng.uniform(-0.5, 0.5)))
            logger.set_velocity_setpoint(sp)
            sent.append((logger.state.t_s, sp))
            next_sp_s = logger.state.t_s + rng.uniform(0.012, 0.03)  # 33-83 Hz, jittered
        logger.step(int(rng.integers(1, 5)) * dt_s)
    log = logger.to_log()
    t = log["t_s"]
    for t_sent, sp in sent:
        row = int(np.searchsorted(t, t_sent))
        assert t[row] == t_sent  # a row at the very step it started to act
        assert log["cmd_vel_n_mps"][row] == pytest.approx(sp.vel_mps[0])

    replay = Simulator(config, seed=11)
    _offboard(OnboardLogger(replay))
    assert replay.state.t_s == t[start_row]
    for k in range(start_row, log.n_rows - 1):
        cmd = tuple(float(log[c][k]) for c in ("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps"))
        replay.set_velocity_setpoint(VelocitySetpoint(cmd, float(log["cmd_yaw_rate_radps"][k])))
        replay.step(t[k + 1] - t[k])
        assert replay.state.t_s == pytest.approx(t[k + 1], abs=1e-9)
    final = log.n_rows - 1
    assert replay.state.vel_ned_mps == pytest.approx(
        [log[c][final] for c in ("vel_n_mps", "vel_e_mps", "vel_d_mps")], abs=1e-9
    )


def test_a_bad_rate_is_refused():
    with pytest.raises(ValueError, match="onboard log rate"):
        OnboardLogger(Simulator(load_sim_config("iris")), rate_hz=0.0)


def test_an_infinite_rate_is_refused():
    with pytest.raises(ValueError, match="onboard log rate"):
        OnboardLogger(Simulator(load_sim_config("iris")), rate_hz=math.inf)


def test_the_log_keeps_its_rate_when_the_steps_do_not_divide_its_period():
    """Steps of 30 ms and a 25 Hz log (40 ms): rows fall on the first step at or past each
    40 ms mark, so 3 s hold 75 rows (not one per 60 ms, 50 rows), and the log says its rate."""
    sim = Simulator(load_sim_config("iris"), seed=0)
    logger = OnboardLogger(sim, rate_hz=25.0)
    for _ in range(100):
        logger.step(0.03)
    log = logger.to_log()
    assert log.n_rows == pytest.approx(75, abs=1)
    assert log.metadata["rate_hz"] == 25.0


def test_streamed_rows_are_on_disk_as_they_are_logged_and_a_copy_leaves_the_stream(tmp_path):
    stream = tmp_path / "live.csv"
    logger = OnboardLogger(Simulator(load_sim_config("iris"), seed=0), 25.0, stream_path=stream)
    for _ in range(50):
        logger.step(0.02)
    rows = logger.to_log().n_rows
    assert len(stream.read_text().splitlines()) == 1 + rows  # header, then every row so far
    copy = tmp_path / "copy.csv"
    assert logger.write(copy) == copy
    assert read_flight_log(copy).n_rows == rows
    assert logger.write(stream) == stream and read_flight_log(stream).n_rows == rows
