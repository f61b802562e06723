"""PX4-rover-like rate control: a speed loop and a yaw-rate loop ([PX4-rover] rate tuning:
feed-forward of the setpoint plus PI on the measured value, the setpoint limited by
RO_YAW_RATE_LIM and the speed limit, slew-limited by the acceleration limits).

Pure: :meth:`RateController.update` takes setpoints and measurements, returns the wheel-speed
and differential yaw-rate commands the drive should produce.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vehicle_sim.rover.presets import RoverPreset


@dataclass
class RateControllerState:
    """Integrators and slew-limited setpoints."""

    speed_integral: float = 0.0
    yaw_rate_integral: float = 0.0
    speed_sp_mps: float = 0.0
    yaw_rate_sp_radps: float = 0.0


class RateController:
    """Speed and yaw-rate PI loops with feed-forward for one preset."""

    def __init__(self, preset: RoverPreset) -> None:
        self.preset = preset
        self.state = RateControllerState()

    def reset(self) -> None:
        self.state = RateControllerState()

    def update(
        self,
        speed_sp_mps: float,
        yaw_rate_sp_radps: float,
        speed_mps: float,
        yaw_rate_radps: float,
        dt_s: float,
    ) -> tuple[float, float]:
        """Wheel speed [m/s] and differential yaw rate [rad/s] commands for the drive."""
        p, s = self.preset, self.state
        v_sp = float(np.clip(speed_sp_mps, -p.max_speed_mps, p.max_speed_mps))
        w_sp = float(np.clip(yaw_rate_sp_radps, -p.max_yaw_rate_radps, p.max_yaw_rate_radps))
        dv = p.max_accel_mps2 * dt_s
        dw = p.max_yaw_accel_radps2 * dt_s
        s.speed_sp_mps += float(np.clip(v_sp - s.speed_sp_mps, -dv, dv))
        s.yaw_rate_sp_radps += float(np.clip(w_sp - s.yaw_rate_sp_radps, -dw, dw))
        ev = s.speed_sp_mps - speed_mps
        ew = s.yaw_rate_sp_radps - yaw_rate_radps
        s.speed_integral = float(np.clip(s.speed_integral + p.speed_i * ev * dt_s, -0.5, 0.5))
        s.yaw_rate_integral = float(
            np.clip(s.yaw_rate_integral + p.yaw_rate_i * ew * dt_s, -0.5, 0.5)
        )
        wheel_speed = s.speed_sp_mps + p.speed_p * ev + s.speed_integral
        wheel_yaw = s.yaw_rate_sp_radps + p.yaw_rate_p * ew + s.yaw_rate_integral
        return (
            float(np.clip(wheel_speed, -p.max_speed_mps, p.max_speed_mps)),
            float(np.clip(wheel_yaw, -p.max_yaw_rate_radps, p.max_yaw_rate_radps)),
        )
