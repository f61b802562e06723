"""Benchmark of the in-process simulator: simulated seconds per wall-clock second.

Flies the default preset (iris) with the full flight control at the default 2 ms step, as the
companion's in-process link does: a velocity setpoint and one log row every 50 ms, velocity
steps of 2 m/s in changing directions. Compilation (numba, cached) is done before timing.
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
        vel = STEP_PATTERN_MPS[(i * len(STEP_PATTERN_MPS) * 5 // max(n, 1)) % 4]
        cmd = VelocitySetpoint(vel)
        sim.set_velocity_setpoint(cmd)
        sim.step(CONTROL_PERIOD_S)
        sim.log_row(cmd)


def _airborne(seed: int) -> Simulator:
    sim = Simulator(load_sim_config("iris"), seed=seed)
    sim.arm()
    sim.takeoff()
    sim.step(6.0)
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.set_mode(FlightMode.OFFBOARD)
    return sim


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """Measure ``sim_realtime_factor`` (simulated s per wall s, higher is better)."""
    flight_s = 10.0 if quick else 60.0
    progress("sim: compiling / warming up")
    _fly(_airborne(seed=0), 1.0)
    sim = _airborne(seed=1)
    progress(f"sim: flying {flight_s:.0f} s of velocity steps at a 2 ms physics step")
    t0 = time.perf_counter()
    _fly(sim, flight_s)
    wall_s = time.perf_counter() - t0
    factor = flight_s / wall_s
    progress(f"sim: {factor:.0f}x real time")
    return {"sim_realtime_factor": factor}
