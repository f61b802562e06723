"""Re-anchoring a simulated vehicle at a measured state, for replaying logged setpoints from it.

:class:`AnchorState` is what a flight log tells about the vehicle at one instant;
``Simulator.anchor`` puts the simulation into it. This module holds the pure parts: validation
and the velocity-loop integral under which the flight control commands a measured thrust vector.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, get_args

import numpy as np

from vehicle_sim import flight_control as fc

IntegralMode = Literal["keep", "reset", "match_thrust"]
INTEGRAL_MODES: tuple[str, ...] = get_args(IntegralMode)
QUAT_NORM_TOLERANCE = 1e-2
"""Largest deviation of |q| from 1 that is normalised away rather than rejected."""
MIN_VERTICAL_THRUST_NORM = 1e-3
"""Below this upward share of the normalised thrust vector the integral is not matched."""


@dataclass(frozen=True)
class AnchorState:
    """A measured vehicle state to put the simulation into (fields are converted to floats).

    Attributes:
        pos_ned_m: (3,) position NED [m].
        vel_ned_mps: (3,) velocity NED [m/s].
        q_wxyz: (4,) attitude, body(FRD)-to-NED; normalised if within 1 % of unit length.
        rates_frd_radps: (3,) body rates FRD [rad/s].
        thrust_n: total rotor thrust [N] (>= 0); the rotor speeds are scaled so that the
            nominal rotor model gives it (0 or None: rotor speeds kept).
        acc_ned_mps2: (3,) measured acceleration NED [m/s^2], the input of the velocity loop's
            D term at the next step (None: the simulated acceleration is kept).
        physics_state: (13,) position, velocity, quaternion and rates as the simulator's state
            vector holds them (:mod:`vehicle_sim.physics`, entries POS to RATES + 3), built once
            here, since a replay anchors at the same states again and again.

    Raises:
        ValueError: a wrong length, a non-finite value, a negative thrust or a quaternion that
            is not of unit length.
    """

    pos_ned_m: tuple[float, ...]
    vel_ned_mps: tuple[float, ...]
    q_wxyz: tuple[float, ...]
    rates_frd_radps: tuple[float, ...] = (0.0, 0.0, 0.0)
    thrust_n: float | None = None
    acc_ned_mps2: tuple[float, ...] | None = None
    physics_state: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name, size in (
            ("pos_ned_m", 3),
            ("vel_ned_mps", 3),
            ("q_wxyz", 4),
            ("rates_frd_radps", 3),
            ("acc_ned_mps2", 3),
        ):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _finite_vector(name, value, size))
        norm = math.sqrt(sum(c * c for c in self.q_wxyz))
        if abs(norm - 1.0) > QUAT_NORM_TOLERANCE:
            raise ValueError(f"q_wxyz {self.q_wxyz} has norm {norm:.4g}; give a unit quaternion")
        object.__setattr__(self, "q_wxyz", tuple(c / norm for c in self.q_wxyz))
        if self.thrust_n is not None:
            thrust_n = float(self.thrust_n)
            if not (math.isfinite(thrust_n) and thrust_n >= 0.0):
                raise ValueError(f"thrust_n {self.thrust_n!r} must be finite and >= 0 N")
            object.__setattr__(self, "thrust_n", thrust_n)
        measured = (*self.pos_ned_m, *self.vel_ned_mps, *self.q_wxyz, *self.rates_frd_radps)
        physics_state = np.array(measured)
        physics_state.setflags(write=False)
        object.__setattr__(self, "physics_state", physics_state)


def check_integral_mode(integral: str, state: AnchorState) -> None:
    """Raise ValueError for an unknown mode, or "match_thrust" without thrust or acceleration."""
    if integral not in INTEGRAL_MODES:
        raise ValueError(f"integral mode {integral!r} unknown; use one of {INTEGRAL_MODES}")
    if integral == "match_thrust" and (state.thrust_n is None or state.acc_ned_mps2 is None):
        raise ValueError('integral="match_thrust" needs thrust_n and acc_ned_mps2 in the anchor')


def velocity_integral_for_thrust(
    state: AnchorState, vel_sp_ned_mps: np.ndarray, thrust_norm_ned: np.ndarray, cp: np.ndarray
) -> np.ndarray | None:
    """The velocity integral [m/s^2] (3,) under which the velocity loop, at ``state`` and with
    setpoint ``vel_sp_ned_mps`` (3,), commands the normalised thrust vector ``thrust_norm_ned``
    (3,) (the inverse of ``flight_control.velocity_control`` before its limits); None when that
    vector has no upward share to invert."""
    thr = thrust_norm_ned
    if thr[2] > -MIN_VERTICAL_THRUST_NORM:
        return None
    g, hover = cp[fc.C_G], cp[fc.C_THR_HOVER]
    acc_sp = np.array([-g * thr[0] / thr[2], -g * thr[1] / thr[2], g * (thr[2] + hover) / hover])
    err = vel_sp_ned_mps - np.array(state.vel_ned_mps)
    kp = np.array([cp[fc.C_VEL_P_XY], cp[fc.C_VEL_P_XY], cp[fc.C_VEL_P_Z]])
    kd = np.array([cp[fc.C_VEL_D_XY], cp[fc.C_VEL_D_XY], cp[fc.C_VEL_D_Z]])
    return acc_sp - kp * err + kd * np.array(state.acc_ned_mps2)


def body_z_ned(q_wxyz: tuple[float, ...]) -> np.ndarray:
    """(3,) the body z axis (down, FRD) in NED for the unit quaternion ``q_wxyz``."""
    w, x, y, z = q_wxyz
    return np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def _finite_vector(name: str, value: object, size: int) -> tuple[float, ...]:
    try:
        out = tuple(float(v) for v in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ValueError(f"{name} {value!r} must be {size} numbers") from None
    if len(out) != size or not all(math.isfinite(v) for v in out):
        raise ValueError(f"{name} {value!r} must be {size} finite numbers")
    return out
