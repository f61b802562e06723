"""The force residual that a set of airframe effects predicts (see :mod:`.forces`).

With the true mass rho * m_nom (payload), a thrust factor f (battery sag, ground effect) and the
drag force D (rotor and body drag on the air-relative velocity, wind included), the vehicle
obeys rho * m_nom * (a - g) = f * F_T + D, with F_T = R [0, 0, -T] the logged thrust force, so

    r = (1 - rho) * m_nom * (a - g) + (f - 1) * F_T + D.

Effects are given as ``{name: {param: value}}`` with the parameter names of vehicle_sim's
effects; absent effects are neutral. The physics is each effect class's own NumPy version of the
equations the simulator integrates (``air_velocity_ned``, ``drag_force_body``, ``thrust_factor``,
``mass_ratio_of``); a test checks the two agree for every effect. Random gusts (zero mean) add
nothing; command-path effects act through the replay, not here.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from diagnosis.forces import GRAVITY_MPS2, ForceData
from vehicle_sim.effects import EFFECT_CLASSES, Effect
from vehicle_sim.effects.base import effect_from_mapping

EffectParams = Mapping[str, Mapping[str, float | tuple[float, ...]]]
MODELLED_ROLES = ("force", "disturbance")  # effects whose air or force the model includes


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


def effect_objects(effects: EffectParams) -> list[Effect]:
    """The effect objects of ``effects`` that act on the force residual, in registry order
    (missing parameters take their defaults, as in the simulator)."""
    return [
        effect_from_mapping(cls, effects[name])
        for name, cls in EFFECT_CLASSES.items()
        if name in effects and cls.ROLE in MODELLED_ROLES
    ]


def drag_force_ned(effects: Sequence[Effect], data: ForceData) -> np.ndarray:
    """(n, 3) drag force in NED [N] of ``effects`` on the air-relative velocity."""
    pos = data.positions()
    air = data.vel_ned_mps
    for e in effects:
        wind = e.air_velocity_ned(pos)
        if wind is not None:
            air = air - wind
    vb = np.einsum("nji,nj->ni", data.rot, air)
    fb = np.zeros_like(vb)
    for e in effects:
        f = e.drag_force_body(vb)
        if f is not None:
            fb = fb + f
    return np.einsum("nij,nj->ni", data.rot, fb)


def thrust_factor(effects: Sequence[Effect], data: ForceData, battery: BatteryModel) -> np.ndarray:
    """(n,) true thrust / nominal thrust (battery sag, ground effect)."""
    f = np.ones(data.n_rows)
    discharge = battery.discharge(data.battery_v)
    for e in effects:
        g = e.thrust_factor(data.alt_m, discharge)
        if g is not None:
            f = f * g
    return f


def predicted_residual(effects: EffectParams, data: ForceData, battery: BatteryModel) -> np.ndarray:
    """(n, 3) force residual [N] that ``effects`` predict for the rows of ``data``."""
    objs = effect_objects(effects)
    rho = math.prod(e.mass_ratio_of() for e in objs)
    g = np.array([0.0, 0.0, GRAVITY_MPS2])
    inertial = (1.0 - rho) * data.mass_kg * (data.acc_regressor() - g)
    thrust_force = data.thrust_axis_ned() * data.thrust_regressor()[:, None]
    f = thrust_factor(objs, data, battery)
    return inertial + (f - 1.0)[:, None] * thrust_force + drag_force_ned(objs, data)


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
