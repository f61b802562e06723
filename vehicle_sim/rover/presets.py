"""Rover presets in [Ostafew16]'s mass range (section 5.1): Husky, ROC6, DMRV.

Numbers are plausible stand-ins, not manufacturer data: mass and wheelbase from [Ostafew16]
section 5.1, speed/turn limits and actuator lags chosen so the heavier robots are slower to
respond. The rate-loop gains follow the structure of [PX4-rover] (feed-forward plus PI on the
measured speed and yaw rate).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RoverPreset:
    """One ground robot.

    Attributes:
        name: preset name.
        steering: "skid" (differential / skid-steer) or "ackermann".
        mass_kg: nominal mass [kg].
        wheelbase_m: distance between axles [m] (Ackermann: used in [Ostafew16] eq. 32).
        max_speed_mps: drive speed limit [m/s].
        max_accel_mps2: longitudinal acceleration limit [m/s^2].
        max_yaw_rate_radps: yaw-rate limit of a skid-steer robot [rad/s].
        max_yaw_accel_radps2: yaw acceleration limit [rad/s^2].
        max_steer_rad: Ackermann steering-angle limit [rad].
        max_steer_rate_radps: Ackermann steering rate limit [rad/s].
        drive_tau_s: first-order lag of the drive (wheel speed) response [s].
        yaw_tau_s: first-order lag of the yaw-rate (differential / steering) response [s].
        speed_p, speed_i: speed-loop gains [1], [1/s] ([PX4-rover] RO_SPEED_P / RO_SPEED_I).
        yaw_rate_p, yaw_rate_i: yaw-rate loop gains [1], [1/s] ([PX4-rover] RO_YAW_RATE_P/_I).
    """

    name: str
    steering: str
    mass_kg: float
    wheelbase_m: float
    max_speed_mps: float
    max_accel_mps2: float
    max_yaw_rate_radps: float
    max_yaw_accel_radps2: float
    max_steer_rad: float
    max_steer_rate_radps: float
    drive_tau_s: float
    yaw_tau_s: float
    speed_p: float = 0.5
    speed_i: float = 0.2
    yaw_rate_p: float = 0.3
    yaw_rate_i: float = 0.1

    def __post_init__(self) -> None:
        if self.steering not in ("skid", "ackermann"):
            raise ValueError(f"steering must be 'skid' or 'ackermann', got {self.steering!r}")
        for f in ("mass_kg", "wheelbase_m", "max_speed_mps", "max_accel_mps2", "drive_tau_s"):
            if not getattr(self, f) > 0:
                raise ValueError(f"{f} must be > 0, got {getattr(self, f)}")


PRESETS: dict[str, RoverPreset] = {
    p.name: p
    for p in (
        RoverPreset("husky_50kg", "skid", 50.0, 0.5, 1.0, 1.0, 1.5, 3.0, 0.0, 0.0, 0.25, 0.3),
        RoverPreset("roc6_150kg", "skid", 150.0, 1.5, 1.6, 0.8, 1.2, 2.0, 0.0, 0.0, 0.4, 0.45),
        RoverPreset("dmrv_600kg", "ackermann", 600.0, 2.0, 2.0, 0.6, 0.9, 1.5, 0.6, 0.5, 0.6, 0.5),
    )
}


def rover_preset(name: str) -> RoverPreset:
    """A preset by name; an unknown name raises ValueError listing the choices."""
    if name not in PRESETS:
        raise ValueError(f"unknown rover preset {name!r}; choose one of {', '.join(PRESETS)}")
    return PRESETS[name]
