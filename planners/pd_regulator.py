"""Paper 000's PD regulator baseline: velocity command from position error.

v_cmd = Kp e - Kd v, with e = p_ref(t) - p and v the measured velocity (horizontal and
vertical gains apart), the whole velocity scaled down to ``max_speed_mps``; yaw rate is a
P term on the wrapped yaw error, clipped to ``max_yaw_rate_radps``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from planners.plan_result import PlanResult, safe_result
from planners.reference import PlannerState, Reference

_NX, _NU = 4, 4


@dataclass(frozen=True)
class PdGains:
    """Gains [1/s] and damping [-] of the PD regulator, and its output limits."""

    kp_horizontal: float = 1.2
    kd_horizontal: float = 0.25
    kp_vertical: float = 0.9
    kd_vertical: float = 0.25
    kp_yaw: float = 1.0
    max_speed_mps: float = 1.5
    max_yaw_rate_radps: float = 1.0

    def __post_init__(self) -> None:
        if not (self.max_speed_mps > 0 and self.max_yaw_rate_radps > 0):
            raise ValueError(
                f"limits must be > 0, got max_speed_mps={self.max_speed_mps}, "
                f"max_yaw_rate_radps={self.max_yaw_rate_radps}"
            )


class PdRegulator:
    """The PD baseline behind the :class:`~planners.reference.Planner` contract.

    Commands are (vel_n, vel_e, vel_d [m/s], yaw_rate [rad/s]); there is no prediction, so
    ``predicted_trajectory`` has shape (0, 4).
    """

    def __init__(self, gains: PdGains | None = None) -> None:
        self.gains = gains or PdGains()
        g = self.gains
        self._kp = np.array([g.kp_horizontal, g.kp_horizontal, g.kp_vertical])
        self._kd = np.array([g.kd_horizontal, g.kd_horizontal, g.kd_vertical])

    def plan(self, state: PlannerState, reference: Reference, t_s: float) -> PlanResult:
        """One regulator step at ``t_s`` [s]; never raises."""
        start = time.perf_counter()
        try:
            if not (state.is_finite() and np.isfinite(t_s)):
                return safe_result(_NU, _NX, "non-finite state or time")
            x_ref = reference.x_ref(float(t_s))
            err = x_ref[:3] - np.asarray(state.pos_ned_m, dtype=float)
            vel = self._kp * err - self._kd * np.asarray(state.vel_ned_mps, dtype=float)
            speed = np.linalg.norm(vel)
            if speed > self.gains.max_speed_mps:
                vel *= self.gains.max_speed_mps / speed
            yaw_err = np.angle(np.exp(1j * (x_ref[3] - state.yaw_rad)))
            lim = self.gains.max_yaw_rate_radps
            yaw_rate = float(np.clip(self.gains.kp_yaw * yaw_err, -lim, lim))
            cmd = np.append(vel, yaw_rate)
            if not np.all(np.isfinite(cmd)):
                return safe_result(_NU, _NX, "non-finite reference")
            elapsed = time.perf_counter() - start
            return PlanResult(cmd, np.zeros((0, _NX)), True, "", elapsed, np.zeros((0, _NU)))
        except Exception as err:  # the flight loop must get a command, whatever happened
            return safe_result(_NU, _NX, f"regulator error: {type(err).__name__}: {err}")
