"""The history GP of [Ostafew16] over experience bins: what the LB-NMPC learns trial to trial.

Query a_k = (s_k, v_act_{k-1}, omega_act_{k-1}, v_cmd_k, omega_cmd_k, omega_cmd_{k-1}): the
path position (arc length, standing in for x_k, which the vertex bins already localise), the
velocity state one step ago from consecutive localised poses ([Ostafew16] section 4.1), and the
command now and one step ago. Output: the body-frame disturbance rates (along [m/s], lateral
[m/s], yaw [rad/s]) observed as (x_{k+1} - f(x_k, u_k)) / dt. Experiences are kept in
gp.local_gp bins with [Ostafew16] section 5.2's c_vertex 5, c_velocity 1, v_bin 0.25 m/s,
c_bin 4; one local GP is built per control step from at most 11 * 3 * 4 = 132 experiences.
Hyperparameters are fixed (section 3.3 finds them offline; ours were set once by hand).
"""

from __future__ import annotations

import math

import numpy as np

from gp.kernels import SquaredExponentialARD
from gp.local_gp import ExperienceBinsConfig, LocalGP
from gp.posterior import Posterior

PAPER_BINS = ExperienceBinsConfig(
    speed_bin_mps=0.25, bin_capacity=4, vertex_window=5, speed_window=1
)
QUERY_NAMES = ("s_m", "v_act_prev_mps", "w_act_prev_radps", "v_cmd_mps", "w_cmd_radps",
               "w_cmd_prev_radps")  # fmt: skip
_LENGTHSCALES = np.array([0.5, 1.0, 1.5, 0.5, 0.8, 1.5])
_SIGNAL_STD = (0.15, 0.15, 0.4)
_NOISE_STD = (0.06, 0.06, 0.1)


def make_history_gp(bins: ExperienceBinsConfig = PAPER_BINS) -> LocalGP:
    """A LocalGP for the rover's three disturbance outputs."""
    kernels = [SquaredExponentialARD(_LENGTHSCALES, s**2) for s in _SIGNAL_STD]
    return LocalGP(kernels, [s**2 for s in _NOISE_STD], bins)


def observed_disturbance(
    pose_k: np.ndarray, pose_k1: np.ndarray, v_cmd_mps: float, w_cmd_radps: float, dt_s: float
) -> np.ndarray:
    """g_k (3,): body-frame rates by which the next pose differs from the unicycle model."""
    c, s = math.cos(pose_k[2]), math.sin(pose_k[2])
    dx, dy = (pose_k1[:2] - pose_k[:2]) / dt_s
    dth = math.atan2(math.sin(pose_k1[2] - pose_k[2]), math.cos(pose_k1[2] - pose_k[2])) / dt_s
    return np.array([c * dx + s * dy - v_cmd_mps, -s * dx + c * dy, dth - w_cmd_radps])


def velocity_state(pose_prev: np.ndarray, pose: np.ndarray, dt_s: float) -> tuple[float, float]:
    """(v_act, omega_act) from two consecutive poses ([Ostafew16] section 4.1)."""
    v = math.hypot(*(pose[:2] - pose_prev[:2])) / dt_s
    dth = math.atan2(math.sin(pose[2] - pose_prev[2]), math.cos(pose[2] - pose_prev[2]))
    return v, dth / dt_s


def horizon_queries(
    s0_m: float,
    poses: np.ndarray,
    pose_prev: np.ndarray,
    v_cmd_mps: np.ndarray,
    w_cmd_radps: np.ndarray,
    w_prev_radps: float,
    dt_s: float,
) -> np.ndarray:
    """Queries a_{k+b} (K, 6) along a predicted trajectory ``poses`` (K+1, 3) (pose 0 = now)."""
    K = len(v_cmd_mps)
    prev = np.vstack([pose_prev[None, :], poses[:-1]])
    out = np.empty((K, 6))
    s = s0_m
    for b in range(K):
        v_act, w_act = velocity_state(prev[b], poses[b], dt_s)
        out[b] = (s, v_act, w_act, v_cmd_mps[b], w_cmd_radps[b],
                  w_prev_radps if b == 0 else w_cmd_radps[b - 1])  # fmt: skip
        s += v_cmd_mps[b] * dt_s
    return out


def predict(post: Posterior | None, queries: np.ndarray) -> np.ndarray:
    """Disturbance means (K, 3); zero without experience (the first trial)."""
    if post is None:
        return np.zeros((queries.shape[0], 3))
    mean, _ = post.predict(queries)
    return mean
