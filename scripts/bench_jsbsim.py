"""Benchmark of the JSBSim backend: simulated seconds per wall-clock second.

Measured like ``bench_sim`` (the built-in physics): the full PX4-like flight control at the
default 2 ms step, a velocity setpoint and one log row every 50 ms, velocity steps of 2 m/s in
changing directions; here it flies JSBSim's F450 (preset "f450"). Compilation (numba, cached) and
JSBSim's model loading are done before timing.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from vehicle_sim import FlightMode, Simulator, VelocitySetpoint, load_sim_config

CONTROL_PERIOD_S = 0.05
STEP_PATTERN_MPS = ((2.0, 0.0, 0.0), (0.0, 2.0, 0.0), (-2.0, 0.0, -0.5), (0.0, -2.0, 0.5))


def _fly(sim: Simulator, duration_s: float) -> None:
    n = round(duration_s / CONTROL_PERIOD_S)
    for i in range(n):
        cmd = VelocitySetpoint(STEP_PATTERN_MPS[(i * len(STEP_PATTERN_MPS) * 5 // n) % 4])
        sim.set_velocity_setpoint(cmd)
        sim.step(CONTROL_PERIOD_S)
        sim.log_row(cmd)


def _airborne() -> Simulator:
    sim = Simulator(load_sim_config("f450"), backend="jsbsim")
    sim.arm()
    sim.takeoff()
    sim.step(6.0)
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.set_mode(FlightMode.OFFBOARD)
    return sim


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """Measure ``jsbsim_realtime_factor`` (simulated s per wall s, higher is better)."""
    flight_s = 5.0 if quick else 30.0
    progress("jsbsim: compiling / warming up")
    _fly(_airborne(), 1.0)
    sim = _airborne()
    progress(f"jsbsim: flying {flight_s:.0f} s of velocity steps at a 2 ms control step")
    t0 = time.perf_counter()
    _fly(sim, flight_s)
    wall_s = time.perf_counter() - t0
    factor = flight_s / wall_s
    progress(f"jsbsim: {factor:.0f}x real time")
    return {"jsbsim_realtime_factor": factor}
