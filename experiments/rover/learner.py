"""The history GP of [Ostafew16] over experience bins: what the LB-NMPC learns trial to trial.

Query a_k = (s_k, e_L,k, e_H,k, v_act_{k-1}, omega_act_{k-1}, v_cmd_k, omega_cmd_k,
omega_cmd_{k-1}) (planners.rover.unicycle_nmpc.QUERY_NAMES): the pose x_k in path coordinates
(arc length and the errors against the nearest vertex), the velocity state one step ago from
consecutive localised poses ([Ostafew16] section 4.1), and the command now and one step ago.
Output: the body-frame disturbance rates (along [m/s], lateral [m/s], yaw [rad/s]) observed as
(x_{k+1} - f(x_k, u_k)) / dt ([Ostafew16] eq. 21). Experiences are kept in gp.local_gp bins with
[Ostafew16] section 5.2's c_vertex 5, c_velocity 1, v_bin 0.25 m/s, c_bin 4; one local GP is
built per control step from at most 11 * 3 * 4 = 132 experiences (:class:`LocalDisturbance`:
the mean and its derivative w.r.t. the query, [Ostafew16] eq. 25 and the SE kernel's gradient,
which the NMPC's Gauss-Newton step needs, eq. 6). Hyperparameters are fixed (section 3.3 finds
them offline; ours were set once by hand).
"""

from __future__ import annotations

import math

import numpy as np
from scipy import linalg
from scipy.linalg.lapack import dpotrf, dpotrs

from gp.kernels import SquaredExponentialARD
from gp.local_gp import ExperienceBinsConfig, LocalGP
from planners.rover.unicycle_nmpc import N_QUERY, QUERY_NAMES

__all__ = ["QUERY_NAMES", "LocalDisturbance", "make_history_gp", "observed_disturbance"]

PAPER_BINS = ExperienceBinsConfig(
    speed_bin_mps=0.25, bin_capacity=4, vertex_window=5, speed_window=1
)
_LENGTHSCALES = np.array([0.5, 0.3, 0.3, 1.0, 1.5, 0.5, 0.8, 1.5])
_SIGNAL_STD = (0.15, 0.15, 0.4)
_NOISE_STD = (0.06, 0.06, 0.1)


def make_history_gp(bins: ExperienceBinsConfig = PAPER_BINS) -> LocalGP:
    """A LocalGP for the rover's three disturbance outputs."""
    kernels = [SquaredExponentialARD(_LENGTHSCALES, s**2) for s in _SIGNAL_STD]
    return LocalGP(kernels, [s**2 for s in _NOISE_STD], bins)


class LocalDisturbance:
    """The local GP's posterior mean g(a) (3,) and Jacobian dg/da (3, 8) at one query.

    mean_j(a) = sum_i alpha_ji k_j(a, a_i),  d mean_j / da = -sum_i alpha_ji k_j(a, a_i)
    (a - a_i) / l_j^2, with alpha_j = (K_j + s2_j I)^-1 g_j over the local experiences.

    Args:
        gp: the experience bins and kernels.
        vertex: the current path vertex; speed_mps: the scheduled speed there.
    """

    def __init__(self, gp: LocalGP, vertex: int, speed_mps: float, jacobian: bool = True) -> None:
        self._jacobian = jacobian
        X, Y = gp.local_data(vertex, speed_mps)
        self.n_experiences = int(X.shape[0])
        ls = np.stack([k.lengthscales for k in gp.kernels])  # (3, d)
        self._shared = bool(np.all(ls == ls[0]))
        self._X, self._inv_l2, self._inv_l = X, 1.0 / ls**2, 1.0 / ls[0]
        self._Xs = X * self._inv_l  # support scaled by the (shared) lengthscales
        if self.n_experiences == 0:
            self._alpha = np.zeros((3, 0))
            return
        if self._shared:  # one kernel matrix serves all outputs: C_j = s2_j E + n2_j I
            k0 = gp.kernels[0]
            E = k0(X, X) / k0.variance
        alphas = []
        for j, (k, s2) in enumerate(zip(gp.kernels, gp.noise_variances, strict=True)):
            C = k.variance * E if self._shared else k(X, X)
            C.flat[:: self.n_experiences + 1] += s2  # the diagonal
            # LAPACK's potrf/potrs directly: what linalg.cho_factor / cho_solve call, without
            # their per-call argument checks and copies (about 0.1 ms of each control step)
            L, info = dpotrf(C, lower=1, clean=0, overwrite_a=1)
            if info == 0:
                alpha, info = dpotrs(L, Y[:, j], lower=1)
            if info != 0:
                raise linalg.LinAlgError(f"local GP kernel matrix not positive definite ({info})")
            alphas.append(alpha * k.variance)
        self._alpha = np.stack(alphas)  # (3, n), each scaled by its signal variance

    @property
    def has_jacobian(self) -> bool:
        return self._jacobian and self.n_experiences > 0

    def mean_and_jacobian(self, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if self.n_experiences == 0:
            return np.zeros(3), np.zeros((3, N_QUERY))
        if self._shared:
            diff = query * self._inv_l - self._Xs  # (n, d), scaled
            w = self._alpha * np.exp(-0.5 * np.einsum("ij,ij->i", diff, diff))  # (3, n)
            if not self._jacobian:
                return w.sum(axis=1), np.zeros((3, N_QUERY))
            return w.sum(axis=1), -(w @ diff) * self._inv_l
        diff = query[None, :] - self._X  # (n, d)
        d2 = (diff * diff) @ self._inv_l2.T  # (n, 3)
        w = np.exp(-0.5 * d2).T * self._alpha  # (3, n)
        jac = -(w @ diff) * self._inv_l2 if self._jacobian else np.zeros((3, N_QUERY))
        return w.sum(axis=1), jac

    def mean(self, queries: np.ndarray) -> np.ndarray:
        """Means (n, 3) at queries (n, 8)."""
        return np.array([self.mean_and_jacobian(q)[0] for q in np.atleast_2d(queries)])


def observed_disturbance(
    pose_k: np.ndarray, pose_k1: np.ndarray, v_cmd_mps: float, w_cmd_radps: float, dt_s: float
) -> np.ndarray:
    """g_k (3,): body-frame rates by which the next pose differs from the unicycle model."""
    c, s = math.cos(pose_k[2]), math.sin(pose_k[2])
    dx, dy = (pose_k1[:2] - pose_k[:2]) / dt_s
    dth = math.atan2(math.sin(pose_k1[2] - pose_k[2]), math.cos(pose_k1[2] - pose_k[2])) / dt_s
    return np.array([c * dx + s * dy - v_cmd_mps, -s * dx + c * dy, dth - w_cmd_radps])


def experience_query(
    s_m: float,
    e_lat_m: float,
    e_head_rad: float,
    pose_prev: np.ndarray,
    pose: np.ndarray,
    v_cmd_mps: float,
    w_cmd_radps: float,
    w_cmd_prev_radps: float,
    dt_s: float,
) -> np.ndarray:
    """a_k (8,) of one step as it happened (the same layout the NMPC predicts with)."""
    v_act = math.hypot(*(pose[:2] - pose_prev[:2])) / dt_s
    dth = math.atan2(math.sin(pose[2] - pose_prev[2]), math.cos(pose[2] - pose_prev[2]))
    return np.array(
        [s_m, e_lat_m, e_head_rad, v_act, dth / dt_s, v_cmd_mps, w_cmd_radps, w_cmd_prev_radps]
    )


def store_pass(gp: LocalGP, experiences: list) -> None:
    """Add one pass's experiences to the bins, after the pass.

    ``experiences`` holds (vertex, v_cmd [m/s], a (8,), g (3,)). Trial j drives on the
    experience of trials < j only ([Ostafew16] section 3.2's D^(1..j-1); the first trial has
    none). Per (vertex, speed bin) a pass adds ONE experience, the mean query and mean observed
    disturbance of its steps there, so a bin of c_bin holds the last c_bin PASSES: at 10 Hz
    and 0.25 m vertices one pass makes ~6 experiences per vertex at 0.4 m/s, which would
    otherwise fill every bin from the last pass alone, and the local GP would model only the
    previous trial's transients (measured: experiment 1's max lateral error then drifts back
    up from trial 5). The mean rather than one of them: each observation carries the
    localisation's frame-to-frame error divided by dt (about 0.03 m/s at 10 Hz, against
    disturbances of 0.05-0.15 m/s), which the mean of n steps cuts by sqrt(n); keeping only
    the step nearest the vertex left experiment 1's max e_L at 0.052 and 0.054 m over trials
    11-20 (seeds 0 and 1), the mean at 0.045 and 0.048 m (BENCHMARKS.md, issue 16).
    """
    groups: dict[tuple[int, int], list] = {}
    for e in experiences:
        groups.setdefault((int(e[0]), gp.config.speed_bin(e[1])), []).append(e)
    for (vtx, _), group in sorted(groups.items()):
        a = np.mean([e[2] for e in group], axis=0)
        g = np.mean([e[3] for e in group], axis=0)
        gp.add(vtx, float(np.mean([e[1] for e in group])), a, g)
