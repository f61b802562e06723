"""Benchmark of the in-process simulator: simulated seconds per wall-clock second.

Flies the default preset (iris) with the full flight control at the default 2 ms step, as the
companion's in-process link does: a velocity setpoint and one log row every 50 ms, velocity
steps of 2 m/s in changing directions. Compilation (numba, cached) is done before timing.
``scripts/bench_jsbsim.py`` flies the same pattern on the JSBSim backend with
:func:`measure_realtime_factor`.
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


def _airborne(preset: str, backend: str, seed: int) -> Simulator:
    sim = Simulator(load_sim_config(preset), seed=seed, backend=backend)
    sim.arm()
    sim.takeoff()
    sim.step(6.0)
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.set_mode(FlightMode.OFFBOARD)
    return sim


def measure_realtime_factor(
    preset: str, backend: str, flight_s: float, progress: Callable[[str], None], label: str
) -> float:
    """Simulated seconds per wall second over ``flight_s`` of velocity steps (after a warm-up)."""
    progress(f"{label}: compiling / warming up")
    _fly(_airborne(preset, backend, seed=0), 1.0)
    sim = _airborne(preset, backend, seed=1)
    progress(f"{label}: flying {flight_s:.0f} s of velocity steps ({preset}, {backend})")
    t0 = time.perf_counter()
    _fly(sim, flight_s)
    factor = flight_s / (time.perf_counter() - t0)
    progress(f"{label}: {factor:.0f}x real time")
    return factor


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """Measure ``sim_realtime_factor`` (simulated s per wall s, higher is better)."""
    flight_s = 10.0 if quick else 60.0
    factor = measure_realtime_factor("iris", "builtin", flight_s, progress, "sim")
    return {"sim_realtime_factor": factor}
