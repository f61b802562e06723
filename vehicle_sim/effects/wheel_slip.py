"""wheel_slip: a skid-steer rover's turning slip and centrifugal side slip.

A skid-steered robot turns about instantaneous centres of rotation (ICRs) of its two wheel
sides that lie outside the wheels, so it yaws at the differential wheel rate divided by an
expansion factor chi >= 1 ([Mandow07]); the ICRs move with the path's curvature and the
robot's speed ([Wang15], on a Pioneer P3-AT) and longitudinally with the centripetal
acceleration, which slides the robot outwards of the turn. Here 1 / chi is ``yaw_scale``,
linear in |v| and |curvature|, and the ICRs' longitudinal shift is ``lat_slip_s`` * v
(sideways speed lat_slip_s * v * omega). The coefficients are not fitted to any robot.

[Mandow07]: A. Mandow, J. L. Martinez, J. Morales, J. L. Blanco, A. Garcia-Cerezo,
J. Gonzalez, "Experimental kinematics for wheeled skid-steer mobile robots", IROS 2007.
[Wang15]: T. Wang, Y. Wu, J. Liang, C. Han, J. Chen, Q. Zhao, "Analysis and experimental
kinematics of a skid-steering wheeled robot based on a laser scanner sensor", Sensors 15(5),
9681-9702, 2015.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from vehicle_sim.effects.base import Effect, ParamSpec, validate_effect
from vehicle_sim.effects.terrain import TerrainEffect


@dataclass(frozen=True)
class WheelSlip(Effect):
    """Skid-steer turning slip growing with speed and curvature, plus centrifugal side slip.

    yaw_scale = 1 - min(0.9, yaw_loss_per_mps |v| + yaw_loss_per_curv_m |omega / v|);
    lateral drift = -lat_slip_s * v * omega (outwards of the turn).
    """

    name: ClassVar[str] = "wheel_slip"
    PARAMS: ClassVar[tuple[ParamSpec, ...]] = (
        ParamSpec("yaw_loss_per_mps", "s/m", 1, 0.0, 0.8, "yaw efficiency lost per m/s"),
        ParamSpec("yaw_loss_per_curv_m", "m", 1, 0.0, 0.8, "yaw efficiency lost per 1/m"),
        ParamSpec("lat_slip_s", "s", 1, 0.0, 1.0, "side-slip velocity per (v * omega)"),
    )
    VEHICLE: ClassVar[str] = "rover"
    ROLE: ClassVar[str] = "terrain"
    NEEDS: ClassVar[tuple[str, ...]] = ("ground_speed_span", "turns")
    EXCITE: ClassVar[str] = "drive turns of several radii at several speeds"
    yaw_loss_per_mps: float = 0.15
    yaw_loss_per_curv_m: float = 0.2
    lat_slip_s: float = 0.1

    def __post_init__(self) -> None:
        validate_effect(self)

    def terrain(
        self, x_m: float, y_m: float, heading_rad: float, speed_mps: float, yaw_rate_radps: float
    ) -> TerrainEffect:
        v = abs(speed_mps)
        curv = abs(yaw_rate_radps) / max(v, 0.1)
        loss = min(0.9, self.yaw_loss_per_mps * v + self.yaw_loss_per_curv_m * min(curv, 2.0))
        return TerrainEffect(
            yaw_scale=1.0 - loss, lat_drift_mps=-self.lat_slip_s * speed_mps * yaw_rate_radps
        )
