"""What one control step decided: the command sent and the planner's account of it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from companion.link import ZERO_VELOCITY, VelocityCommand


@dataclass(frozen=True)
class Decision:
    """A command and why.

    Attributes:
        command: the velocity command sent this step.
        ok: False when ``command`` is the safe command (zero velocity: brake and hover).
        reason: empty when ok, otherwise why the safe command was sent.
        solve_time_s: planner computation time this step [s] (0 when no planner ran).
        ref_pos_ned_m: (3,) reference position at this step, or None outside reference flight.
        pred_pos_ned_m, pred_vel_ned_mps: (3,) the planner's one-step prediction, or None when
            the planner makes none.
    """

    command: VelocityCommand
    ok: bool = True
    reason: str = ""
    solve_time_s: float = 0.0
    ref_pos_ned_m: np.ndarray | None = None
    pred_pos_ned_m: np.ndarray | None = None
    pred_vel_ned_mps: np.ndarray | None = None


def safe_decision(reason: str, **extra: object) -> Decision:
    """The brake/hover decision (zero velocity, zero yaw rate) with its reason."""
    return Decision(ZERO_VELOCITY, ok=False, reason=reason, **extra)


@dataclass(frozen=True)
class CommandLimits:
    """Saturation applied to every planner command before it is sent.

    Attributes:
        horizontal_mps: limit on the horizontal speed (norm of north, east) [m/s].
        up_mps, down_mps: limits on climb and descent speed [m/s], both positive.
        yaw_rate_radps: limit on |yaw rate| [rad/s].
    """

    horizontal_mps: float
    up_mps: float = 1.5
    down_mps: float = 1.0
    yaw_rate_radps: float = 1.0

    def apply(self, vel_ned_mps: np.ndarray, yaw_rate_radps: float) -> VelocityCommand:
        """The command saturated to these limits (direction of horizontal motion kept)."""
        v = np.asarray(vel_ned_mps, dtype=float)
        horizontal = float(np.hypot(v[0], v[1]))
        scale = min(1.0, self.horizontal_mps / horizontal) if horizontal > 0.0 else 1.0
        down = float(np.clip(v[2], -self.up_mps, self.down_mps))
        yaw_rate = float(np.clip(yaw_rate_radps, -self.yaw_rate_radps, self.yaw_rate_radps))
        return VelocityCommand((float(v[0] * scale), float(v[1] * scale), down), yaw_rate)


class HoverPolicy:
    """Zero velocity every step: the setpoint stream sent before switching to OFFBOARD.

    ``hold_pos_ned_m`` (3,) is logged as the reference: where the vehicle is meant to stay.
    """

    def __init__(self, hold_pos_ned_m: np.ndarray) -> None:
        self._hold_pos_ned_m = np.asarray(hold_pos_ned_m, dtype=float).copy()

    def decide(self, state: object, t_s: float) -> Decision:
        return Decision(ZERO_VELOCITY, ref_pos_ned_m=self._hold_pos_ned_m)
