"""Benchmark of the JSBSim backend: simulated seconds per wall-clock second, and the learning
loop on a plant we did not write.

``jsbsim_realtime_factor`` is measured exactly like ``bench_sim`` (same flight, full PX4-like
flight control, a setpoint and a log row every 50 ms), on JSBSim's F450 (preset "f450",
backend "jsbsim"). Compilation and JSBSim's model loading are done before timing.

``jsbsim_tracking_gain`` and ``jsbsim_tracking_gain_min``: a reduced study (paper000 regime)
on ``f450_jsbsim``: each trajectory flown nominal, the model learned (identified lag + GP,
low_speed, the one selection the study fits and flies: the figures read no other; gated by its
multi-step prediction on held-out flights, then by a closed-loop check: flown on the training
seeds, it must track no worse than the identified lag alone, or the lag flies without it), then
flown augmented on other seeds. The closed-loop check is
the study's default because of this bench: on the F450 a GP on the velocity and the command
(state_input, the regime's features then) passed the open-loop check (0.024 vs 0.045 m over
2 s) and flew 0.041-0.049 m where the lag alone flies 0.021-0.029 m and nominal 0.034-0.045 m
(BENCHMARKS.md, session 11); refused, the lag flew: 1.59 / 1.41. The regime's GP now gets the
velocity only and earns its place here (BENCHMARKS.md, session 12). Per trajectory, the gain
is the nominal tracking RMSE divided by the learned one; the figures are their mean and minimum.
The study's report (which model flew and why) is kept in out/bench/jsbsim_study/. The study's
trial-to-trial view ([Ostafew16]) is not flown: no figure here reads it (it was a third of the
bench's flights, BENCHMARKS.md, session 22).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from experiments.bench.sim import measure_realtime_factor
from experiments.study.config import SELECTIONS, StudyConfig
from experiments.study.paper000 import NOMINAL
from experiments.study.run import run_study

JSBSIM_VEHICLE = "f450_jsbsim"
STUDY_OUT = Path("out/bench/jsbsim_study")  # the learning loop's study report, kept


def tracking_gains(flights: dict[str, list], planner: str) -> np.ndarray:
    """Per trajectory: mean nominal tracking RMSE / mean ``planner`` tracking RMSE."""
    trajectories = sorted({f.trajectory for f in flights[NOMINAL]})
    gains = []
    for i in trajectories:
        nom = np.mean([f.tracking_rmse_m for f in flights[NOMINAL] if f.trajectory == i])
        aug = np.mean([f.tracking_rmse_m for f in flights[planner] if f.trajectory == i])
        gains.append(nom / aug)
    return np.asarray(gains)


def learning_loop_gains(progress: Callable[[str], None], quick: bool = False) -> dict[str, float]:
    """``jsbsim_tracking_gain`` (mean over trajectories) and ``jsbsim_tracking_gain_min``."""
    config = StudyConfig(
        out_dir=STUDY_OUT,
        vehicle=JSBSIM_VEHICLE,
        n_trajectories=4,
        repeats=2,
        selections=SELECTIONS[:1],
        n_trials=0,
    )
    if quick:
        config = replace(config.quick(), n_trials=0)
    progress(f"jsbsim: learning loop on {JSBSIM_VEHICLE}, {config.n_trajectories} trajectories")
    result = run_study(config, progress)
    gains = tracking_gains(result.paper000.flights, config.selections[0])
    return {
        "jsbsim_tracking_gain": float(gains.mean()),
        "jsbsim_tracking_gain_min": float(gains.min()),
    }


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """``jsbsim_realtime_factor`` (simulated s per wall s, higher is better) and the learning
    loop's tracking gains."""
    flight_s = 5.0 if quick else 30.0
    factor = measure_realtime_factor("f450", "jsbsim", flight_s, progress, "jsbsim")
    return {"jsbsim_realtime_factor": factor, **learning_loop_gains(progress, quick)}
