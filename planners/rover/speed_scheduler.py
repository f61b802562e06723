"""Experience-based speed scheduler ([Ostafew16] section 4.2, eq. 31, Table I).

After trial j, the speed at each path vertex goes up by gamma_up where the robot passed it with
small errors, small turn commands and enough matched features, down by gamma_down where any of
them crossed its threshold scaled by the deadband lambda_db, and stays otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SpeedSchedulerConfig:
    """Gains and thresholds ([Ostafew16] Table I, experiment 2 defaults).

    Attributes:
        gamma_up_mps, gamma_down_mps: speed increase / decrease per trial [m/s].
        lambda_lat_m, lambda_head_rad: error thresholds [m], [rad].
        lambda_features: matched-feature threshold [count].
        lambda_omega_radps: turn-command threshold [rad/s].
        lambda_db: deadband factor (> 1).
        v_init_mps: first-trial speed everywhere [m/s].
        v_min_mps, v_max_mps: bounds of the schedule [m/s]. Table I gives neither; the paper
            reports scheduled speeds of 0.35 to 1.2 m/s over all its robots (abstract;
            experiment 3: 0.5 to 1.2 m/s), never below the first trial's speed, so v_min is
            v_init. Lower floors hurt: an Ackermann robot's turning authority
            v tan(delta_max) / L shrinks with speed (measured with a 0.2 m/s floor: experiment
            3's robot left the path at 0.2-0.25 m/s in a 4 m-radius arc; when side slopes
            slipped at a fixed rate rather than an angle, experiments 2 and 3 also sat at
            0.2 m/s over them, their crab atan(0.12 / 0.2) = 0.54 rad holding e_H > lambda_H).
    """

    gamma_up_mps: float = 0.15
    gamma_down_mps: float = 0.1
    lambda_lat_m: float = 0.15
    lambda_head_rad: float = math.radians(10.0)
    lambda_features: float = 30.0
    lambda_omega_radps: float = 1.0
    lambda_db: float = 1.1
    v_init_mps: float = 0.35
    v_min_mps: float = 0.35
    v_max_mps: float = 1.2

    def __post_init__(self) -> None:
        if not self.lambda_db > 1:
            raise ValueError(f"lambda_db must be > 1, got {self.lambda_db}")
        if self.lambda_features < 3:
            raise ValueError(f"lambda_features must be >= 3, got {self.lambda_features}")
        if not 0 < self.v_min_mps <= self.v_init_mps <= self.v_max_mps:
            raise ValueError("need 0 < v_min_mps <= v_init_mps <= v_max_mps")


TABLE_I: dict[str, SpeedSchedulerConfig] = {
    "experiment_2": SpeedSchedulerConfig(),
    # [Ostafew16] section 5.5 and Fig. 17: the DMRV drove "at speeds ranging from 0.5 to 1.2
    # m/s", so its first trial (and floor) is 0.5 m/s; the 0.35 m/s start is experiment 2's.
    "experiment_3": SpeedSchedulerConfig(
        gamma_up_mps=0.2, gamma_down_mps=0.15, v_init_mps=0.5, v_min_mps=0.5
    ),
}


def initial_schedule(n_vertices: int, config: SpeedSchedulerConfig) -> np.ndarray:
    """v_sched^(1): v_init everywhere, (n_vertices,) [m/s]."""
    return np.full(n_vertices, config.v_init_mps)


def next_schedule(
    v_sched_mps: np.ndarray,
    e_lat_m: np.ndarray,
    e_head_rad: np.ndarray,
    omega_cmd_radps: np.ndarray,
    features: np.ndarray,
    config: SpeedSchedulerConfig,
) -> np.ndarray:
    """[Ostafew16] eq. 31: the schedule for trial j+1 from trial j's per-vertex records (N,).

    Records are the worst values seen at each vertex (largest |errors| and |omega|, fewest
    features); a vertex never passed (NaN) keeps its speed.
    """
    c = config
    el, eh, om = np.abs(e_lat_m), np.abs(e_head_rad), np.abs(omega_cmd_radps)
    seen = np.isfinite(el) & np.isfinite(eh) & np.isfinite(om) & np.isfinite(features)
    with np.errstate(invalid="ignore"):
        up = (
            (el < c.lambda_lat_m)
            & (eh < c.lambda_head_rad)
            & (om < c.lambda_omega_radps)
            & (features > c.lambda_features)
        )
        down = (
            (el > c.lambda_lat_m * c.lambda_db)
            | (eh > c.lambda_head_rad * c.lambda_db)
            | (om > c.lambda_omega_radps * c.lambda_db)
            | (features < c.lambda_features / c.lambda_db)
        )
    out = v_sched_mps.astype(float).copy()
    out[seen & up] += c.gamma_up_mps
    out[seen & down & ~up] -= c.gamma_down_mps
    return np.clip(out, c.v_min_mps, c.v_max_mps)
