"""The reference and planner contracts shared by the PD regulator and the NMPC."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from planners.plan_result import PlanResult


@dataclass(frozen=True)
class ReferenceSample:
    """A reference sampled at n times (NED, SI).

    Attributes:
        pos_ned_m: positions, shape (n, 3).
        vel_ned_mps: velocities, shape (n, 3).
        acc_ned_mps2: accelerations, shape (n, 3).
        yaw_rad: yaw angles, shape (n,).
        yaw_rate_radps: yaw rates, shape (n,).
    """

    pos_ned_m: np.ndarray
    vel_ned_mps: np.ndarray
    acc_ned_mps2: np.ndarray
    yaw_rad: np.ndarray
    yaw_rate_radps: np.ndarray


class Reference(Protocol):
    """A time-parametrised reference trajectory (t in seconds from its start).

    ``x_ref``/``u_ref`` follow the 4-DOF kinematic model: x = (pos_n, pos_e, pos_d [m], yaw
    [rad]) and u = (vel_n, vel_e, vel_d [m/s], yaw_rate [rad/s]). Before t = 0 and after the
    end the reference holds its end points at rest.
    """

    @property
    def duration_s(self) -> float: ...

    def sample(self, t_s: np.ndarray | float) -> ReferenceSample: ...

    def x_ref(self, t_s: np.ndarray | float) -> np.ndarray:
        """Shape (4,) for a scalar t, (n, 4) for n times."""
        ...

    def u_ref(self, t_s: np.ndarray | float) -> np.ndarray:
        """Shape (4,) for a scalar t, (n, 4) for n times."""
        ...


class SampledReference:
    """Base for references that implement ``sample``: derives ``x_ref`` and ``u_ref`` from it."""

    def sample(self, t_s: np.ndarray | float) -> ReferenceSample:
        raise NotImplementedError(f"{type(self).__name__} must implement sample(t_s)")

    def x_ref(self, t_s: np.ndarray | float) -> np.ndarray:
        """(pos_n, pos_e, pos_d [m], yaw [rad]): shape (4,) for scalar t, else (n, 4)."""
        smp = self.sample(t_s)
        out = np.column_stack([smp.pos_ned_m, smp.yaw_rad])
        return out[0] if np.ndim(t_s) == 0 else out

    def u_ref(self, t_s: np.ndarray | float) -> np.ndarray:
        """(vel_n, vel_e, vel_d [m/s], yaw_rate [rad/s]): shape (4,) for scalar t, else (n, 4)."""
        smp = self.sample(t_s)
        out = np.column_stack([smp.vel_ned_mps, smp.yaw_rate_radps])
        return out[0] if np.ndim(t_s) == 0 else out


@dataclass(frozen=True)
class PlannerState:
    """The vehicle state a planner sees (NED, SI).

    ``vel_int_mps2`` (3,): the autopilot's velocity integrator as the companion keeps it (for a
    model that carries it, planners.nominal_models.px4_velocity_pi); None reads as zeros.
    ``vel_prev_ned_mps`` (3,) [m/s]: the velocity measured one planner interval ago (for a
    model that carries it, planners.velocity_history); None reads as ``vel_ned_mps``.
    """

    pos_ned_m: np.ndarray
    vel_ned_mps: np.ndarray
    yaw_rad: float
    vel_int_mps2: np.ndarray | None = None
    vel_prev_ned_mps: np.ndarray | None = None

    def is_finite(self) -> bool:
        """True when every element is finite (no NaN or inf)."""
        return bool(
            np.isfinite(self.pos_ned_m).all()
            and np.isfinite(self.vel_ned_mps).all()
            and np.isfinite(self.yaw_rad)
        )


class Planner(Protocol):
    """One planning step: state and reference in, command out. Never raises on bad input."""

    def plan(self, state: PlannerState, reference: Reference, t_s: float) -> PlanResult: ...
