"""RoverSim: a ground robot driven by speed + yaw-rate setpoints, like a PX4 rover in offboard.

Per physics step (``physics_dt_s``): the rate controller turns setpoints into wheel-speed and
differential-yaw (skid) or steering-angle (Ackermann, [Ostafew16] eq. 32 inverted) commands; the
drive follows them through first-order lags with rate limits; the terrain effects scale the
achieved speed and yaw rate and add sideways drift; the pose integrates the planar kinematics
with that drift. Deterministic for a seed (the seed drives only the rate-measurement noise).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from vehicle_sim.effects import RoverPayload
from vehicle_sim.effects.terrain import NEUTRAL, TerrainEffect
from vehicle_sim.rover.control import RateController
from vehicle_sim.rover.presets import RoverPreset


@dataclass(frozen=True)
class RoverState:
    """Truth state.

    Attributes:
        t_s: simulated time [s].
        x_m, y_m: position in the world frame [m] (x east-like, y north-like; heading from +x).
        heading_rad: yaw, counter-clockwise from +x [rad], wrapped to (-pi, pi].
        speed_mps: ground speed along the body x axis [m/s].
        lat_speed_mps: ground speed along the body left axis [m/s].
        yaw_rate_radps: yaw rate [rad/s].
        steer_rad: Ackermann steering angle [rad] (0 for skid-steer).
    """

    t_s: float
    x_m: float
    y_m: float
    heading_rad: float
    speed_mps: float
    lat_speed_mps: float
    yaw_rate_radps: float
    steer_rad: float


class RoverSim:
    """Simulated rover: preset + terrain effects + PX4-like rate control.

    Args:
        preset: the robot.
        effects: rover effects (vehicle_sim.effects with VEHICLE "rover"); rover_payload
            scales lags and limits.
        seed: seed of the rate-measurement noise.
        physics_dt_s: integration step [s].
        rate_noise_std: std of the speed [m/s] and yaw-rate [rad/s] measurement noise.
        pose: initial (x_m, y_m, heading_rad).
    """

    def __init__(
        self,
        preset: RoverPreset,
        effects: Sequence[object] = (),
        seed: int = 0,
        physics_dt_s: float = 0.01,
        rate_noise_std: float = 0.0,
        pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> None:
        if not physics_dt_s > 0:
            raise ValueError(f"physics_dt_s must be > 0 s, got {physics_dt_s}")
        self.preset = preset
        self.effects = tuple(e for e in effects if not isinstance(e, RoverPayload))
        ratio = math.prod(e.mass_ratio for e in effects if isinstance(e, RoverPayload))
        self._mass_ratio = float(ratio)
        self.physics_dt_s = physics_dt_s
        self.rate_noise_std = rate_noise_std
        self._rng = np.random.default_rng(seed)
        self.controller = RateController(preset)
        self.armed = False
        self._sp = (0.0, 0.0)
        self._wheel_speed = 0.0
        self._wheel_yaw = 0.0
        self._steer = 0.0
        self.state = RoverState(0.0, *pose, 0.0, 0.0, 0.0, 0.0)

    # --- commands ---------------------------------------------------------------------------
    def arm(self) -> None:
        self.armed = True

    def disarm(self) -> None:
        self.armed = False
        self._sp = (0.0, 0.0)
        self.controller.reset()

    def set_setpoint(self, speed_mps: float, yaw_rate_radps: float) -> None:
        """Offboard setpoint: forward speed [m/s] and yaw rate [rad/s] (held until replaced)."""
        if not (math.isfinite(speed_mps) and math.isfinite(yaw_rate_radps)):
            raise ValueError(f"setpoint must be finite, got {speed_mps}, {yaw_rate_radps}")
        self._sp = (float(speed_mps), float(yaw_rate_radps))

    def terrain_at(self, state: RoverState) -> TerrainEffect:
        """The combined terrain effect at a state."""
        out = NEUTRAL
        for e in self.effects:
            out = out.combine(
                e.terrain(
                    state.x_m, state.y_m, state.heading_rad, state.speed_mps, state.yaw_rate_radps
                )
            )
        return out

    # --- dynamics -----------------------------------------------------------------------------
    def step(self, duration_s: float) -> RoverState:
        """Advance by ``duration_s`` (rounded to whole physics steps); returns the new state."""
        n = max(1, round(duration_s / self.physics_dt_s))
        for _ in range(n):
            self._physics_step(self.physics_dt_s)
        return self.state

    def _physics_step(self, dt: float) -> None:
        p, st = self.preset, self.state
        noise = (
            self.rate_noise_std * self._rng.standard_normal(2) if self.rate_noise_std else (0, 0)
        )
        if self.armed:
            wheel_cmd, yaw_cmd = self.controller.update(
                self._sp[0], self._sp[1], st.speed_mps + noise[0], st.yaw_rate_radps + noise[1], dt
            )
        else:
            wheel_cmd, yaw_cmd = 0.0, 0.0
        r = self._mass_ratio
        a_max = p.max_accel_mps2 / r
        dv = (wheel_cmd - self._wheel_speed) * dt / (p.drive_tau_s * r)
        self._wheel_speed += float(np.clip(dv, -a_max * dt, a_max * dt))
        terrain = self.terrain_at(st)
        speed = self._wheel_speed * terrain.speed_scale
        if p.steering == "skid":
            dw = (yaw_cmd - self._wheel_yaw) * dt / (p.yaw_tau_s * r)
            lim = p.max_yaw_accel_radps2 / r * dt
            self._wheel_yaw += float(np.clip(dw, -lim, lim))
            yaw_rate = self._wheel_yaw * terrain.yaw_scale
        else:
            # [Ostafew16] eq. 32: delta = atan(L omega / v), on the commanded speed, signed as
            # PX4's Ackermann setpoint (forward speed < 0 backwards): reversing, the wheels
            # turn the other way for the same yaw rate
            v_ref = max(abs(self._sp[0]), abs(self._wheel_speed), 0.2)
            if (self._sp[0] or self._wheel_speed) < 0.0:
                v_ref = -v_ref
            steer_cmd = math.atan(p.wheelbase_m * yaw_cmd / v_ref)
            steer_cmd = float(np.clip(steer_cmd, -p.max_steer_rad, p.max_steer_rad))
            ds = (steer_cmd - self._steer) * dt / p.yaw_tau_s
            lim = p.max_steer_rate_radps * dt
            self._steer += float(np.clip(ds, -lim, lim))
            yaw_rate = speed * math.tan(self._steer) / p.wheelbase_m * terrain.yaw_scale
        lat = terrain.lat_drift_mps
        c, s = math.cos(st.heading_rad), math.sin(st.heading_rad)
        heading = st.heading_rad + yaw_rate * dt
        heading = math.atan2(math.sin(heading), math.cos(heading))
        self.state = RoverState(
            t_s=st.t_s + dt,
            x_m=st.x_m + (speed * c - lat * s) * dt,
            y_m=st.y_m + (speed * s + lat * c) * dt,
            heading_rad=heading,
            speed_mps=speed,
            lat_speed_mps=lat,
            yaw_rate_radps=yaw_rate,
            steer_rad=self._steer,
        )
