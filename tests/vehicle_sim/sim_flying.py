"""Flying helpers shared by the vehicle_sim tests."""

from __future__ import annotations

from collections.abc import Callable

from flightlog.schema import FlightLog, FlightLogRecorder
from vehicle_sim import FlightMode, Simulator, VelocitySetpoint, load_sim_config


def hovering(
    effects=None, preset: str = "iris", seed: int = 0, settle_s: float = 12.0, alt_m: float = 2.5
):
    """A simulator that took off to ``alt_m`` and has settled in OFFBOARD at zero velocity."""
    sim = Simulator(load_sim_config(preset, effects), seed=seed)
    assert sim.arm().accepted
    assert sim.takeoff(alt_m).accepted
    for _ in range(round(alt_m / 1.5 + 30)):
        if sim.state.mode is FlightMode.HOLD:
            break
        sim.step(1.0)
    sim.step(2.0)
    fly(sim, (0.0, 0.0, 0.0), 0.1)
    assert sim.set_mode(FlightMode.OFFBOARD).accepted
    fly(sim, (0.0, 0.0, 0.0), settle_s)
    return sim


def fly(sim: Simulator, vel_ned_mps, duration_s: float, period_s: float = 0.05, **kw):
    """Stream a velocity setpoint every ``period_s`` for ``duration_s``; returns the states."""
    states = []
    for _ in range(round(duration_s / period_s)):
        sim.set_velocity_setpoint(VelocitySetpoint(tuple(vel_ned_mps), **kw))
        states.append(sim.step(period_s))
    return states


def record_offboard(
    sim: Simulator,
    command_at: Callable[[float], VelocitySetpoint],
    duration_s: float,
    rate_hz: float,
) -> FlightLog:
    """Stream ``command_at(t)`` (t [s] from the first row) at ``rate_hz`` [Hz] for
    ``duration_s`` and record the log a companion would: each row the state at the tick and
    the command sent then, time from the first row."""
    recorder = FlightLogRecorder({**sim.log_metadata(), "rate_hz": rate_hz})
    t0_s = sim.t_s
    for k in range(round(duration_s * rate_hz)):
        cmd = command_at(k / rate_hz)
        sim.set_velocity_setpoint(cmd)
        row = sim.log_row(cmd)
        row["t_s"] -= t0_s
        recorder.append(row)
        sim.step(1.0 / rate_hz)
    return recorder.to_log()
