"""Benchmark of the JSBSim backend: simulated seconds per wall-clock second.

Measured exactly like ``bench_sim`` (same flight, full PX4-like flight control, a setpoint and a
log row every 50 ms), on JSBSim's F450 (preset "f450", backend "jsbsim"). Compilation and
JSBSim's model loading are done before timing.
"""

from __future__ import annotations

from collections.abc import Callable

from experiments.bench.sim import measure_realtime_factor


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """Measure ``jsbsim_realtime_factor`` (simulated s per wall s, higher is better)."""
    flight_s = 5.0 if quick else 30.0
    factor = measure_realtime_factor("f450", "jsbsim", flight_s, progress, "jsbsim")
    return {"jsbsim_realtime_factor": factor}
