"""How the unicycle NMPC drives each of the three robots, as [Ostafew16]'s experiments drive
them (experiments.rover.scenarios, whose docstring gives the measurements that chose the
weights and horizons). A module of its own so that `rover-path` over MAVLink picks the rover's
tuning without importing the simulator the scenarios' terrain comes from.
"""

from __future__ import annotations

from dataclasses import dataclass

from planners.rover.unicycle_nmpc import UnicycleNmpcConfig


@dataclass(frozen=True)
class RoverTuning:
    """How the NMPC drives one robot.

    Attributes:
        nmpc: weights, horizon and limits.
        feedforward: the turn-rate penalty is measured from the path's v * curvature instead
            of from zero; the weights were chosen with it (a heavy r_omega measured from zero
            pulls the robot inside every arc: see experiments.rover.scenarios).
    """

    nmpc: UnicycleNmpcConfig
    feedforward: bool = False


# Per robot preset (vehicle_sim.rover), as the three experiments drive them.
NMPC_TUNING = {
    "husky_50kg": RoverTuning(UnicycleNmpcConfig(horizon=25, q_lat=40.0, q_head=1.0,
                                                 r_omega=0.5, r_delta=1.0,
                                                 omega_max_radps=1.5), feedforward=True),
    "roc6_150kg": RoverTuning(UnicycleNmpcConfig(horizon=35, q_lat=20.0, q_head=1.0,
                                                 r_omega=2.0, r_delta=4.0,
                                                 omega_max_radps=1.2)),
    "dmrv_600kg": RoverTuning(UnicycleNmpcConfig(horizon=40, q_lat=10.0, q_head=1.0,
                                                 r_omega=10.0, r_delta=10.0,
                                                 omega_max_radps=0.9), feedforward=True),
}  # fmt: skip


def tuning_for(preset: str) -> RoverTuning:
    """The NMPC tuning of the experiment that drives rover ``preset`` (above), or the planner's
    defaults (no feedforward) for a rover none of them drives."""
    return NMPC_TUNING.get(preset, RoverTuning(UnicycleNmpcConfig()))
