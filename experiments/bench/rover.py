"""Rover benchmark (`bench --only rover`, also listed under `loop`): [Ostafew16] experiment 1.

Runs rover_exp1 (30 m path, 0.4 m/s, 50 kg skid-steer, LB-NMPC with the history GP over
experience bins) for 20 trials (4 with ``quick``). Figures:
    rover_exp1_max_lateral_reduction   1 - max |e_L| of the last trial / that of trial 1 [-]
    rover_exp1_max_heading_reduction   the same for |e_H| [-]
    rover_exp1_max_lateral_reduction_localised  the same for e_L as the robot's localisation
                                       measures it, [Ostafew16]'s own measure [-]
    rover_exp1_max_lateral_reduction_late_median  the median over trials 11-20 of the same
                                       reduction [-]: [Ostafew16] plots every trial's maximum
                                       (Fig. 10), and which late trial is last moves the
                                       headline figure by +-0.1
    rover_step_median_ms               median wall time of one local GP + NMPC step [ms]
    rover_step_median_cpu_ms           the same step's median CPU time (thread) [ms]: the
                                       cost without the waits of a loaded machine
    rover_max_local_experiences        largest local GP used in any step [count] (<= 132)
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from experiments.rover.report import summarise
from experiments.rover.scenarios import scenario
from experiments.rover.trial import run_trials


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    trials = 4 if quick else 20
    progress(f"rover: experiment 1, {trials} trials")
    s = summarise(run_trials(scenario("rover_exp1").with_trials(trials)))
    return {
        "rover_exp1_max_lateral_reduction": s["max_lateral_reduction"],
        "rover_exp1_max_heading_reduction": s["max_heading_reduction"],
        "rover_exp1_max_lateral_reduction_localised": s["max_lateral_reduction_localised"],
        "rover_exp1_max_lateral_reduction_late_median": float(
            np.median(s["late_lateral_reductions"])
        ),
        "rover_step_median_ms": s["step_median_ms"],
        "rover_step_median_cpu_ms": s["step_median_cpu_ms"],
        "rover_max_local_experiences": float(s["max_local_experiences"]),
    }
