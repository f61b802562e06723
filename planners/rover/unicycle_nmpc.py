"""Path-tracking LB-NMPC on the unicycle model with a learned disturbance ([Ostafew16] eqs. 4-14,
18-20, 30), solved by Gauss-Newton over the turn rates only.

Model per step b (dt = ``dt_s``), with body-frame disturbance rates g_b = g(a_b) = (g_along
[m/s], g_lat [m/s], g_yaw [rad/s]) from the learned model (zero for the plain NMPC):

    x_{b+1} = x_b + dt (cos th_b (v_b + g_along) - sin th_b g_lat)
    y_{b+1} = y_b + dt (sin th_b (v_b + g_along) + cos th_b g_lat)
    th_{b+1} = th_b + dt (omega_b + g_yaw)

and the disturbance query of [Ostafew16] eq. 19, a_b = (x_b, v_{b-1}, u_b, u_{b-1}), laid out as
:data:`QUERY_NAMES`: the pose x_b in path coordinates (arc length s_b, the scheduled advance
from the current fix, and e_L, e_H against the reference pose of step b: the terrain is placed
in the world, so where the robot is across the path and how it is turned matter, not only how
far along it is), the velocity state (v_act, omega_act) one step back from consecutive predicted
poses ([Ostafew16] section 4.1; pose -1 is the previous localised pose), the commanded speed
and turn rate now, and the turn rate one step back.

The speed v_b is fixed to the schedule; only the turn rates omega_0..omega_{K-1} are optimised
([Ostafew16] section 4.1). The cost is a sum of squares, with e_L/e_H of each predicted pose
against its reference pose, the turn rate and its change:
sum_b q_lat e_L^2 + q_head e_H^2 + r omega_b^2 + r_delta (omega_b - omega_{b-1})^2.

Structure: K unknowns. Each Gauss-Newton iteration rolls the model out once and carries the
derivatives of the poses with respect to the K turn rates forward along it (forward-mode, a
(3, K) block per step), including the learned model's derivatives through u_b, u_{b-1} and the
velocity state ([Ostafew16] eq. 6: H_u = df/du + dg/du). Without dg/du the optimiser would treat
the learned disturbance as an exogenous push and could not use what it learned about the
robot's own response (actuator lag, turn-rate loss on loose ground). The K x K normal equations
are solved directly and the turn rates clipped to |omega| <= omega_max (projected Gauss-Newton).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

QUERY_NAMES = ("s_m", "e_lat_m", "e_head_rad", "v_act_prev_mps", "w_act_prev_radps",
               "v_cmd_mps", "w_cmd_radps", "w_cmd_prev_radps")  # fmt: skip
N_QUERY = len(QUERY_NAMES)


class DisturbanceModel(Protocol):
    """A learned disturbance g(a): mean (3,) and its Jacobian (3, 8) at one query a (8,).
    ``has_jacobian`` False says the Jacobian is zero (the solver then skips the chain rule)."""

    @property
    def has_jacobian(self) -> bool: ...

    def mean_and_jacobian(self, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class ConstantDisturbance:
    """A disturbance that does not depend on the query (e.g. a known drift), g (3,)."""

    g: tuple[float, float, float]
    has_jacobian = False

    def mean_and_jacobian(self, query: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(self.g, dtype=float), np.zeros((3, N_QUERY))


@dataclass(frozen=True)
class UnicycleNmpcConfig:
    """Weights and sizes.

    Attributes:
        horizon: K, steps.
        dt_s: step [s].
        q_lat, q_head: weights on e_L^2 [1/m^2] and e_H^2 [1/rad^2].
        r_omega, r_delta: weights on omega^2 and its change^2 [s^2/rad^2].
        omega_max_radps: turn-rate bound [rad/s].
        iterations: Gauss-Newton iterations per solve.
    """

    horizon: int = 15
    dt_s: float = 0.1
    q_lat: float = 30.0
    q_head: float = 10.0
    r_omega: float = 1.0
    r_delta: float = 3.0
    omega_max_radps: float = 1.5
    iterations: int = 2

    def __post_init__(self) -> None:
        if self.horizon < 1 or not self.dt_s > 0 or self.iterations < 1:
            raise ValueError("horizon and iterations must be >= 1 and dt_s > 0")


@dataclass(frozen=True, eq=False)
class Rollout:
    """Predicted poses (K+1, 3), their derivatives (K+1, 3, K) w.r.t. the turn rates, the
    disturbances used (K, 3) and the queries a_b (K, 8)."""

    poses: np.ndarray
    d_poses: np.ndarray
    g: np.ndarray
    queries: np.ndarray


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def rollout(
    x0: np.ndarray,
    pose_prev: np.ndarray,
    s0_m: float,
    v_mps: np.ndarray,
    omega_radps: np.ndarray,
    omega_prev_radps: float,
    dt_s: float,
    model: DisturbanceModel | None = None,
    ref_poses: np.ndarray | None = None,
) -> Rollout:
    """Model (18) along the horizon with forward-mode derivatives w.r.t. omega (K,).

    Args:
        x0: current pose (3,); pose_prev: the localised pose one step earlier (3,).
        s0_m: arc length of the current fix [m].
        v_mps, omega_radps: scheduled speeds and turn rates (K,).
        omega_prev_radps: the turn rate commanded one step earlier.
        model: the learned disturbance, or None for the a-priori model alone.
        ref_poses: path poses (K, 3) the poses 0..K-1 are measured against for the query's
            e_L, e_H (default: zero errors).
    """
    K = len(v_mps)
    v = [float(x) for x in v_mps]
    om = [float(x) for x in omega_radps]
    P = np.empty((K + 1, 3))
    G = np.zeros((K, 3))
    A = np.empty((K, N_QUERY))
    P[0] = x0
    chain = model is not None and model.has_jacobian
    D = np.zeros((K + 1, 3, K))
    rot = np.empty(K)  # dt (d/d theta of the step's x-advance), per step (chain-free form)
    rot_y = np.empty(K)  # the same for y
    x, y, th = (float(c) for c in x0)
    px, py, pth = (float(c) for c in pose_prev)
    d_prev = np.zeros((3, K))
    s = s0_m
    for b in range(K):
        dx, dy = x - px, y - py
        dist = math.hypot(dx, dy)
        w_prev = omega_prev_radps if b == 0 else om[b - 1]
        if ref_poses is not None:
            xr, yr, tr = ref_poses[b]
            sr, cr = math.sin(tr), math.cos(tr)
            e_lat, e_head = -sr * (xr - x) + cr * (yr - y), _wrap(tr - th)
        else:
            sr = cr = e_lat = e_head = 0.0
        A[b] = (s, e_lat, e_head, dist / dt_s, _wrap(th - pth) / dt_s, v[b], om[b], w_prev)
        va, vl = v[b], 0.0
        if model is not None:
            g, J = model.mean_and_jacobian(A[b])
            G[b] = g
            va, vl = va + float(g[0]), float(g[1])
        c, sn = math.cos(th), math.sin(th)
        if chain:  # derivatives through the learned model: carried step by step
            Db = D[b]
            dD = Db - d_prev
            dv_act = (dx * dD[0] + dy * dD[1]) / (max(dist, 1e-9) * dt_s)
            dg = np.outer(J[:, 3], dv_act) + np.outer(J[:, 4], dD[2] / dt_s)
            if ref_poses is not None:
                dg += np.outer(J[:, 1], sr * Db[0] - cr * Db[1]) - np.outer(J[:, 2], Db[2])
            dg[:, b] += J[:, 6]
            if b > 0:
                dg[:, b - 1] += J[:, 7]
            Dn = D[b + 1]
            Dn[0] = Db[0] + dt_s * (-sn * va - c * vl) * Db[2]
            Dn[1] = Db[1] + dt_s * (c * va - sn * vl) * Db[2]
            Dn[2] = Db[2]
            Dn[2, b] += dt_s
            Dn[0] += dt_s * (c * dg[0] - sn * dg[1])
            Dn[1] += dt_s * (sn * dg[0] + c * dg[1])
            Dn[2] += dt_s * dg[2]
            d_prev = Db
        else:
            rot[b] = dt_s * (-sn * va - c * vl)
            rot_y[b] = dt_s * (c * va - sn * vl)
        px, py, pth = x, y, th
        x, y, th = (
            x + dt_s * (c * va - sn * vl),
            y + dt_s * (sn * va + c * vl),
            th + dt_s * (om[b] + float(G[b, 2])),
        )
        P[b + 1] = (x, y, th)
        s += v[b] * dt_s
    if not chain:
        _pose_derivatives(D, rot, rot_y, dt_s)
    return Rollout(P, D, G, A)


def _pose_derivatives(D: np.ndarray, rot: np.ndarray, rot_y: np.ndarray, dt_s: float) -> None:
    """Fill D (K+1, 3, K) with d pose_b / d omega_k when the disturbance does not depend on omega.

    Then d th_b / d omega_k = dt for k < b, and d x_{b+1} = d x_b + rot_b d th_b (rot_b = dt
    d(x-advance)/d th at step b), so d x_b / d omega_k = sum_{k < j < b} rot_j dt: a cumulative
    sum down the steps of the strictly lower-triangular increments, added in the same order as
    the step-by-step recursion (bit for bit the same numbers).
    """
    K = D.shape[2]
    below = np.tri(K, K, -1, dtype=bool)  # [j, k]: k < j
    D[1:, 2] = np.where(np.tri(K, K, 0, dtype=bool), dt_s, 0.0)
    np.cumsum(np.where(below, (rot * dt_s)[:, None], 0.0), axis=0, out=D[1:, 0])
    np.cumsum(np.where(below, (rot_y * dt_s)[:, None], 0.0), axis=0, out=D[1:, 1])


def unicycle_rollout(
    x0: np.ndarray, v_mps: np.ndarray, omega_radps: np.ndarray, g: np.ndarray, dt_s: float
) -> np.ndarray:
    """Predicted poses (K+1, 3) from x0 (3,), speeds (K,), turn rates (K,), disturbances (K, 3)."""
    out = np.empty((len(v_mps) + 1, 3))
    out[0] = x0
    x, y, th = (float(c) for c in x0)
    v_l, w_l = (
        np.asarray(v_mps, dtype=float).tolist(),
        np.asarray(omega_radps, dtype=float).tolist(),
    )
    g_l = np.asarray(g, dtype=float).tolist()
    for b, (v, w, (ga, gl, gy)) in enumerate(zip(v_l, w_l, g_l, strict=True)):
        va, vl, c, sn = v + ga, gl, math.cos(th), math.sin(th)
        x, y, th = (
            x + dt_s * (c * va - sn * vl),
            y + dt_s * (sn * va + c * vl),
            th + dt_s * (w + gy),
        )
        out[b + 1] = (x, y, th)
    return out


Reference = np.ndarray | Callable[[np.ndarray], np.ndarray]


class UnicycleNmpc:
    """The solver; :meth:`solve` returns the optimal turn rates (K,)."""

    def __init__(self, config: UnicycleNmpcConfig = UnicycleNmpcConfig()) -> None:  # noqa: B008
        self.config = config
        c, K = config, config.horizon
        # constant part of the normal equations: r omega^2 + r_delta (omega_b - omega_{b-1})^2
        Dm = np.eye(K) - np.eye(K, k=-1)
        self._H_u = c.r_omega * np.eye(K) + c.r_delta * Dm.T @ Dm
        self._Dm = Dm
        self._warm = np.zeros(K)
        self.last_rollout: Rollout | None = None

    def reset(self) -> None:
        self._warm = np.zeros(self.config.horizon)

    def warm_start(self) -> np.ndarray:
        """The previous solution shifted by one step, (K,)."""
        return np.concatenate([self._warm[1:], self._warm[-1:]])

    def solve(
        self,
        x0: np.ndarray,
        v_mps: np.ndarray,
        ref: Reference,
        omega_prev_radps: float,
        *,
        pose_prev: np.ndarray | None = None,
        s0_m: float = 0.0,
        model: DisturbanceModel | None = None,
        omega_init: np.ndarray | None = None,
        ref0: np.ndarray | None = None,
        omega_ref_radps: np.ndarray | None = None,
    ) -> np.ndarray:
        """Turn rates (K,).

        Args:
            x0: current pose (3,); v_mps: scheduled speeds (K,).
            ref: reference poses (K, 3) for predicted poses 1..K, or a function of the
                predicted poses (K, 3) returning them (evaluated once, on the first rollout:
                e.g. the path pose at each predicted pose's arc length).
            omega_prev_radps: turn rate commanded one step earlier.
            pose_prev: localised pose one step earlier (3,) (default: x0, i.e. at rest).
            s0_m: arc length of the current fix [m] (the query's path position).
            model: learned disturbance, or None.
            omega_init: initial guess (default: the previous solution shifted).
            ref0: the path pose the current pose is measured against (the nearest vertex),
                (3,); default: x0 (zero errors).
            omega_ref_radps: turn rates (K,) the r_omega term is measured from (e.g. the
                path's v * curvature); default zero, i.e. [Ostafew16] eq. 20's u^T R u.
        """
        c = self.config
        x0 = np.asarray(x0, dtype=float)
        pose_prev = x0 if pose_prev is None else np.asarray(pose_prev, dtype=float)
        v = np.asarray(v_mps, dtype=float)
        w = self.warm_start() if omega_init is None else np.asarray(omega_init, dtype=float)
        ql, qh = c.q_lat, c.q_head
        w_ref = 0.0 if omega_ref_radps is None else np.asarray(omega_ref_radps, dtype=float)
        if callable(ref):  # the reference of the nominal prediction (no learned model)
            nominal = unicycle_rollout(x0, v, w, np.zeros((len(v), 3)), c.dt_s)
            ref_arr = np.asarray(ref(nominal[1:]), dtype=float)
        else:
            ref_arr = np.asarray(ref, dtype=float)
        ref_q = np.vstack([x0 if ref0 is None else np.asarray(ref0, dtype=float), ref_arr[:-1]])
        for _ in range(c.iterations):
            ro = rollout(x0, pose_prev, s0_m, v, w, omega_prev_radps, c.dt_s, model, ref_q)
            P, D = ro.poses[1:], ro.d_poses[1:]
            st, ct = np.sin(ref_arr[:, 2]), np.cos(ref_arr[:, 2])
            e_lat = -st * (ref_arr[:, 0] - P[:, 0]) + ct * (ref_arr[:, 1] - P[:, 1])
            e_head = np.arctan2(np.sin(ref_arr[:, 2] - P[:, 2]), np.cos(ref_arr[:, 2] - P[:, 2]))
            J_lat = st[:, None] * D[:, 0] - ct[:, None] * D[:, 1]  # (K, K)
            J_head = -D[:, 2]
            dw = self._Dm @ w
            dw[0] -= omega_prev_radps
            H = ql * J_lat.T @ J_lat + qh * J_head.T @ J_head + self._H_u
            grad = ql * J_lat.T @ e_lat + qh * J_head.T @ e_head
            grad += c.r_omega * (w - w_ref) + c.r_delta * self._Dm.T @ dw
            w = np.clip(w - np.linalg.solve(H, grad), -c.omega_max_radps, c.omega_max_radps)
        self.last_rollout = ro
        self._warm = w
        return w
