"""Map named vehicle quantities onto a nominal model's state and input vectors.

Models name their elements with units (``pos_n_m``, ``vel_e_mps``, ``yaw_rad``, ...); this
module fills those vectors from a :class:`PlannerState` or a :class:`ReferenceSample`, so
the planners work for any of the models in :mod:`planners.nominal_models`.
"""

from __future__ import annotations

import numpy as np

from planners.nominal_models import HISTORY_STATES, INTEGRATOR_STATES, NominalModel
from planners.reference import PlannerState, ReferenceSample

_AXES = {"n": 0, "e": 1, "d": 2}
ANGLE_SUFFIX = "_rad"


def _element(
    name: str, pos: np.ndarray, vel: np.ndarray, yaw, yaw_rate, vel_int=None, vel_prev=None
) -> np.ndarray:
    """One named quantity from (n, 3) positions/velocities/velocity integrators (None: zeros)/
    previous velocities (None: the velocities) and (n,) yaw/yaw rate."""
    if name in INTEGRATOR_STATES:
        axis = INTEGRATOR_STATES.index(name)
        return np.zeros(pos.shape[0]) if vel_int is None else vel_int[:, axis]
    if name in HISTORY_STATES:
        return (vel if vel_prev is None else vel_prev)[:, HISTORY_STATES.index(name)]
    kind, _, axis = name.rpartition("_")[0].partition("_")
    if kind == "pos" and axis in _AXES:
        return pos[:, _AXES[axis]]
    if kind == "vel" and axis in _AXES:
        return vel[:, _AXES[axis]]
    if name in ("yaw_rad", "heading_rad"):
        return np.asarray(yaw, dtype=float)
    if name in ("yaw_rate_radps", "turn_rate_radps"):
        return np.asarray(yaw_rate, dtype=float)
    if name == "speed_mps":
        return np.linalg.norm(vel[:, :2], axis=1)
    raise ValueError(
        f"no mapping for model element {name!r}; known: pos_*_m, vel_*_mps, yaw_rad, "
        "heading_rad, yaw_rate_radps, turn_rate_radps, speed_mps"
    )


def state_vector(model: NominalModel, state: PlannerState) -> np.ndarray:
    """The model state (nx,) for a vehicle state."""
    pos = np.reshape(np.asarray(state.pos_ned_m, dtype=float), (1, 3))
    vel = np.reshape(np.asarray(state.vel_ned_mps, dtype=float), (1, 3))
    vel_int = vel_prev = None
    if state.vel_int_mps2 is not None:
        vel_int = np.reshape(np.asarray(state.vel_int_mps2, dtype=float), (1, 3))
    if state.vel_prev_ned_mps is not None:
        vel_prev = np.reshape(np.asarray(state.vel_prev_ned_mps, dtype=float), (1, 3))
    cols = [
        _element(n, pos, vel, [state.yaw_rad], [0.0], vel_int, vel_prev) for n in model.state_names
    ]
    return np.concatenate(cols)


def reference_vectors(
    model: NominalModel, sample: ReferenceSample, feedforward: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """(x_ref (n, nx), u_ref (n, nu)) for a reference sampled at n times.

    With ``feedforward`` the velocity inputs lead the reference velocity by the model's
    ``velocity_lead_s`` times the reference acceleration (u = v + tau a for a first-order
    lag: the input that keeps the model on the reference), so the input cost does not pull
    the plan behind the reference during accelerations; without it (or for a model with no
    lead) the input reference is the reference velocity. An integrator state's reference is 0,
    a previous velocity's the reference velocity (their default cost weight is 0: the model's
    ``untracked_states``)."""
    args = (sample.pos_ned_m, sample.vel_ned_mps, sample.yaw_rad, sample.yaw_rate_radps)
    x_ref = np.stack([_element(n, *args) for n in model.state_names], axis=1)
    vel = np.asarray(sample.vel_ned_mps, dtype=float)
    if feedforward and model.velocity_lead_s:
        vel = vel + np.asarray(model.velocity_lead_s) * np.asarray(sample.acc_ned_mps2, float)
    args = (sample.pos_ned_m, vel, sample.yaw_rad, sample.yaw_rate_radps)
    u_ref = np.stack([_element(n, *args) for n in model.input_names], axis=1)
    return x_ref, u_ref


def angle_indices(model: NominalModel) -> list[int]:
    """Indices of angle states (names ending in ``_rad``), which wrap at +-pi."""
    return [i for i, n in enumerate(model.state_names) if n.endswith(ANGLE_SUFFIX)]
