"""Flying helpers shared by the vehicle_sim tests."""

from __future__ import annotations

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
