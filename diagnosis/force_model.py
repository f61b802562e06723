"""The force residual that a set of airframe effects predicts (see :mod:`.forces`).

With the true mass rho * m_nom (payload), a thrust factor f (battery sag, ground effect) and the
drag force D (rotor and body drag on the air-relative velocity, wind included), the vehicle
obeys rho * m_nom * (a - g) = f * F_T + D, with F_T = R [0, 0, -T] the logged thrust force, so

    r = (1 - rho) * m_nom * (a - g) + (f - 1) * F_T + D.

Effects are given as ``{name: {param: value}}`` with the parameter names of vehicle_sim's
effects; absent effects are neutral. These are the same equations the simulator integrates.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from diagnosis.forces import GRAVITY_MPS2, ForceData

EffectParams = Mapping[str, Mapping[str, float | tuple[float, ...]]]
ASSUMED_ROTOR_HEIGHT_M = 0.1  # rotor plane above ground when landed, if no config gives it


@dataclass(frozen=True)
class BatteryModel:
    """Battery voltage full and empty [V] (the config's [battery]) to turn the logged voltage
    into a discharge fraction."""

    full_v: float
    empty_v: float

    def discharge(self, battery_v: np.ndarray) -> np.ndarray:
        """(n,) discharge fraction in [0, 1]; NaN where the voltage is unknown."""
        d = (self.full_v - battery_v) / (self.full_v - self.empty_v)
        return np.clip(d, 0.0, 1.0)


def drag_force_ned(effects: EffectParams, data: ForceData) -> np.ndarray:
    """(n, 3) rotor, body and isotropic drag in NED [N] on the air-relative velocity."""
    wind = np.asarray(effects.get("wind", {}).get("vel_ned_mps", (0.0, 0.0, 0.0)), float)
    k = np.asarray(effects.get("rotor_drag", {}).get("k_n_per_mps", (0.0, 0.0, 0.0)), float)
    c = np.asarray(effects.get("body_drag", {}).get("c_n_per_mps2", (0.0, 0.0, 0.0)), float)
    k_iso = float(effects.get("isotropic_drag", {}).get("k_n_per_mps2", 0.0))
    air = data.vel_ned_mps - wind
    vb = np.einsum("nji,nj->ni", data.rot, air)
    fb = -k * vb - c * vb * np.abs(vb)
    iso = -k_iso * np.linalg.norm(air, axis=1, keepdims=True) * air
    return np.einsum("nij,nj->ni", data.rot, fb) + iso


def thrust_factor(effects: EffectParams, data: ForceData, battery: BatteryModel) -> np.ndarray:
    """(n,) true thrust / nominal thrust from battery sag and ground effect."""
    f = np.ones(data.n_rows)
    sag = effects.get("battery_sag")
    if sag is not None:
        f = f - float(sag["max_thrust_loss"]) * battery.discharge(data.battery_v)
    ground = effects.get("ground_effect")
    if ground is not None:
        h = np.maximum(data.alt_m, 0.0) + float(
            ground.get("rotor_height_m", ASSUMED_ROTOR_HEIGHT_M)
        )
        s = np.clip(1.0 - h / (2.0 * float(ground["rotor_radius_m"])), 0.0, None)
        f = f * (1.0 + float(ground["max_gain"]) * s * s)
    return f


def predicted_residual(effects: EffectParams, data: ForceData, battery: BatteryModel) -> np.ndarray:
    """(n, 3) force residual [N] that ``effects`` predict for the rows of ``data``."""
    rho = float(effects.get("payload", {}).get("mass_ratio", 1.0))
    g = np.array([0.0, 0.0, GRAVITY_MPS2])
    inertial = (1.0 - rho) * data.mass_kg * (data.acc_ned_mps2 - g)
    thrust_force = data.thrust_axis_ned() * data.thrust_n[:, None]
    f = thrust_factor(effects, data, battery)
    return inertial + (f - 1.0)[:, None] * thrust_force + drag_force_ned(effects, data)


def flight_time_from_voltage(data: ForceData, battery: BatteryModel) -> float | None:
    """Hover endurance [s] (battery_sag's ``full_flight_time_s``) from the logged voltage.

    The discharge fraction d (from the voltage) grows as the integral of T / (m_nom g) divided
    by the endurance; a least-squares line through the origin per log gives the endurance.
    None when the voltage does not fall.
    """
    num = den = 0.0
    for seg in np.unique(data.segment):
        rows = data.segment == seg
        d = battery.discharge(data.battery_v[rows])
        if not np.all(np.isfinite(d)):
            return None
        load = data.thrust_n[rows] / (data.mass_kg * GRAVITY_MPS2)
        t = data.t_s[rows]
        integral = np.concatenate([[0.0], np.cumsum(0.5 * (load[1:] + load[:-1]) * np.diff(t))])
        num += float(np.sum(integral * integral))
        den += float(np.sum(integral * (d - d[0])))
    return num / den if den > 0.0 else None


def gust_intensity_mps(
    effects: EffectParams, data: ForceData, battery: BatteryModel
) -> float | None:
    """Std [m/s] per horizontal axis of the air velocity that would explain the force residual
    left over by ``effects`` through their rotor drag; None without horizontal rotor drag."""
    k = np.asarray(effects.get("rotor_drag", {}).get("k_n_per_mps", (0.0, 0.0, 0.0)), float)
    if k[0] <= 0.05 or k[1] <= 0.05:
        return None
    left = data.resid_ned_n - predicted_residual(effects, data, battery)
    left_body = np.einsum("nji,nj->ni", data.rot, left)
    gust_body = left_body[:, :2] / k[:2]
    return float(np.sqrt(np.mean(gust_body * gust_body)))
