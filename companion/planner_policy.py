"""A planner inside the control loop, with the guard that keeps the flight safe.

Whatever the planner does - raise, return NaN, return a wrong shape, report ``ok=False`` - the
loop gets a finite command: the planner's (saturated) when it is good, zero velocity (brake
and hover) with a reason otherwise. Nothing from the planner can throw into the flight.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from companion.decision import CommandLimits, Decision, safe_decision
from companion.link import LinkState, VelocityCommand
from planners.reference import Planner, PlannerState, Reference


@runtime_checkable
class OneStepVelocityModel(Protocol):
    """A planner that states the velocity [m/s] (3,) its model predicts one control period
    after a command (3,) is sent at the current velocity (3,) and position (3,) [m]; logged as
    the prediction (e.g. a nominal model augmented with a learned residual, which may depend
    on where the vehicle is)."""

    def one_step_velocity(
        self, vel_ned_mps: np.ndarray, cmd_vel_ned_mps: np.ndarray, pos_ned_m: np.ndarray
    ) -> np.ndarray: ...


class PlannerPolicy:
    """Follow ``reference`` with ``planner``; reference time is loop time minus ``t0_s``.

    Args:
        planner: anything with ``plan(PlannerState, Reference, t_s) -> PlanResult``.
        reference: the trajectory to follow (t = 0 at ``t0_s`` on the loop clock).
        t0_s: loop clock time at which the reference starts [s].
        limits: saturation for the planner's commands.

    The logged one-step velocity prediction is what the planner's ``one_step_velocity`` says
    for the sent command (see :class:`OneStepVelocityModel`), else the command itself (the
    kinematic model flies it at once). Predictions are logged only when the planner returns a
    predicted trajectory. A planner with ``observe_obstacles(ObstacleDistances)`` (an
    obstacle-aware one) is given every range scan the link delivers, before it plans.
    """

    def __init__(
        self,
        planner: Planner,
        reference: Reference,
        t0_s: float,
        limits: CommandLimits,
    ) -> None:
        self._planner = planner
        self._reference = reference
        self._t0_s = t0_s
        self._limits = limits

    def reference_time_s(self, t_s: float) -> float:
        """Reference time [s] at loop time ``t_s``."""
        return t_s - self._t0_s

    def decide(self, state: LinkState, t_s: float) -> Decision:
        t_ref_s = self.reference_time_s(t_s)
        ref_pos = np.asarray(self._reference.x_ref(t_ref_s), dtype=float)[:3]
        if not state.is_finite():
            return safe_decision("non-finite telemetry", ref_pos_ned_m=ref_pos)
        pstate = PlannerState(state.pos_ned_m.copy(), state.vel_ned_mps.copy(), state.yaw_rad)
        try:
            observe = getattr(self._planner, "observe_obstacles", None)
            if observe is not None and state.obstacle_distances is not None:
                observe(state.obstacle_distances)
            result = self._planner.plan(pstate, self._reference, t_ref_s)
        except Exception as exc:  # noqa: BLE001 - a planner bug must not reach the flight
            return safe_decision(
                f"planner raised {type(exc).__name__}: {exc}", ref_pos_ned_m=ref_pos
            )
        solve_time_s = _finite_or_zero(getattr(result, "solve_time_s", 0.0))
        command = np.asarray(result.command, dtype=float).reshape(-1)
        if command.shape != (4,) or not np.all(np.isfinite(command)):
            return safe_decision(
                f"planner returned an unusable command {command.tolist()} (need 4 finite values)",
                solve_time_s=solve_time_s,
                ref_pos_ned_m=ref_pos,
            )
        if not result.ok:
            return safe_decision(
                f"planner failed: {result.reason or 'no reason given'}",
                solve_time_s=solve_time_s,
                ref_pos_ned_m=ref_pos,
            )
        sent = self._limits.apply(command[:3], float(command[3]))
        pred_pos, pred_vel = self._prediction(
            np.asarray(result.predicted_trajectory, float), sent, state
        )
        return Decision(
            sent,
            solve_time_s=solve_time_s,
            ref_pos_ned_m=ref_pos,
            pred_pos_ned_m=pred_pos,
            pred_vel_ned_mps=pred_vel,
        )

    def _prediction(
        self, trajectory: np.ndarray, sent: VelocityCommand, state: LinkState
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """One-step prediction (row 1 of the planned states), or (None, None) without one."""
        if trajectory.ndim != 2 or trajectory.shape[0] < 2 or trajectory.shape[1] < 3:
            return None, None
        row = trajectory[1]
        if not np.all(np.isfinite(row)):
            return None, None
        cmd = np.asarray(sent.vel_ned_mps, dtype=float)
        if isinstance(self._planner, OneStepVelocityModel):
            vel = self._planner.one_step_velocity(state.vel_ned_mps, cmd, state.pos_ned_m)
        else:
            vel = cmd
        return row[:3].copy(), np.asarray(vel, dtype=float).copy()


def _finite_or_zero(value: object) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return 0.0
    return v if np.isfinite(v) else 0.0
