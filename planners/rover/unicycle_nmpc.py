"""Path-tracking NMPC on the unicycle model with a learned disturbance ([Ostafew16] eqs. 18, 30).

Model per step b (dt = ``dt_s``), body-frame disturbance rates g_b = (g_along [m/s],
g_lat [m/s], g_yaw [rad/s]) given by the learned model (zero for the plain NMPC):

    x_{b+1} = x_b + dt (cos th_b (v_b + g_along) - sin th_b g_lat)
    y_{b+1} = y_b + dt (sin th_b (v_b + g_along) + cos th_b g_lat)
    th_{b+1} = th_b + dt (omega_b + g_yaw)

The speed v_b is fixed to the schedule; only the turn rates omega_0..omega_{K-1} are optimised
([Ostafew16] section 4.1). The cost is a sum of squares, with e_L/e_H of each predicted pose
against its reference pose (the path pose at the predicted arc length), the turn rate and its
change:  sum_b q_lat e_L^2 + q_head e_H^2 + r omega_b^2 + r_delta (omega_b - omega_{b-1})^2.
CasADi gives the residuals and their Jacobian; a few projected Gauss-Newton iterations with
|omega| <= omega_max solve it (K unknowns, warm-started from the previous solution).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np


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


def unicycle_rollout(
    x0: np.ndarray, v_mps: np.ndarray, omega_radps: np.ndarray, g: np.ndarray, dt_s: float
) -> np.ndarray:
    """Predicted poses (K+1, 3) from x0 (3,), speeds (K,), turn rates (K,), disturbances (K, 3)."""
    out = np.empty((len(v_mps) + 1, 3))
    out[0] = x0
    for b in range(len(v_mps)):
        x, y, th = out[b]
        va, vl = v_mps[b] + g[b, 0], g[b, 1]
        out[b + 1] = (
            x + dt_s * (np.cos(th) * va - np.sin(th) * vl),
            y + dt_s * (np.sin(th) * va + np.cos(th) * vl),
            th + dt_s * (omega_radps[b] + g[b, 2]),
        )
    return out


class UnicycleNmpc:
    """The solver; ``solve`` returns the optimal turn rates (K,) and the predicted poses."""

    def __init__(self, config: UnicycleNmpcConfig = UnicycleNmpcConfig()) -> None:  # noqa: B008
        self.config = config
        c = config
        K = c.horizon
        w = ca.SX.sym("w", K)
        x0 = ca.SX.sym("x0", 3)
        v = ca.SX.sym("v", K)
        g = ca.SX.sym("g", K, 3)
        ref = ca.SX.sym("ref", K, 3)
        w_prev = ca.SX.sym("w_prev")
        x, y, th = x0[0], x0[1], x0[2]
        res = []
        last = w_prev
        for b in range(K):
            va, vl = v[b] + g[b, 0], g[b, 1]
            x = x + c.dt_s * (ca.cos(th) * va - ca.sin(th) * vl)
            y = y + c.dt_s * (ca.sin(th) * va + ca.cos(th) * vl)
            th = th + c.dt_s * (w[b] + g[b, 2])
            xr, yr, tr = ref[b, 0], ref[b, 1], ref[b, 2]
            e_lat = -ca.sin(tr) * (xr - x) + ca.cos(tr) * (yr - y)
            e_head = ca.atan2(ca.sin(tr - th), ca.cos(tr - th))
            res += [
                np.sqrt(c.q_lat) * e_lat,
                np.sqrt(c.q_head) * e_head,
                np.sqrt(c.r_omega) * w[b],
                np.sqrt(c.r_delta) * (w[b] - last),
            ]
            last = w[b]
        r = ca.vertcat(*res)
        self._fun = ca.Function("lbnmpc_res", [w, x0, v, g, ref, w_prev], [r, ca.jacobian(r, w)])
        self._warm = np.zeros(K)

    def reset(self) -> None:
        self._warm = np.zeros(self.config.horizon)

    def warm_start(self) -> np.ndarray:
        """The previous solution shifted by one step, (K,)."""
        return np.concatenate([self._warm[1:], self._warm[-1:]])

    def solve(
        self,
        x0: np.ndarray,
        v_mps: np.ndarray,
        g: np.ndarray,
        ref: np.ndarray,
        omega_prev_radps: float,
        omega_init: np.ndarray | None = None,
    ) -> np.ndarray:
        """Turn rates (K,): x0 (3,), v_mps (K,), g (K, 3), ref (K, 3) for poses 1..K."""
        c = self.config
        w = self.warm_start() if omega_init is None else np.asarray(omega_init, dtype=float)
        for _ in range(c.iterations):
            r, J = self._fun(w, x0, v_mps, g, ref, omega_prev_radps)
            r, J = np.asarray(r).ravel(), np.asarray(J)
            step = np.linalg.solve(J.T @ J + 1e-6 * np.eye(len(w)), J.T @ r)
            w = np.clip(w - step, -c.omega_max_radps, c.omega_max_radps)
        self._warm = w
        return w
