"""The fast path's Gauss-Newton linearisation, evaluated node-parallel in NumPy.

Multiple shooting makes the N nodes independent: the RK4 step and its Jacobians
(A_k = d x_{k+1} / d x_k, B_k = d x_{k+1} / d u_k) at node k depend only on (x_k, u_k).

With a residual in batched form (``ResidualTerm.batch``, e.g. the GP mean's arrays as data,
gp.batched_mean), each of the four RK4 stages is evaluated for all nodes at once, the Jacobians
carried through the stages by the chain rule:

    F(x) = f(x, u) + B_z g(z(x, u)),   J_s = dF/dx (x_s) D_s,   D_1 = I, D_{s+1} = I + c_s h J_s

(c_s = 1/2, 1/2, 1), with f, its Jacobians and the feature map z(x, u) and its Jacobians from one
small CasADi Function mapped over the nodes (the nominal model: a few dozen operations), and
the residual g with d g / d z from the batched form. A history state (NominalModel.history)
then takes its source's value at the node: its row of A selects the source, its row of B is
zero. Without a batched form (no residual, or a residual given only as a CasADi Function) the
whole interval step (``NmpcFormulation.step``, history included) and its Jacobians are one
CasADi Function mapped over the nodes: one call per linearisation instead of eight, and a
residual whose features do not change within the interval (e.g. the commanded velocity) is
evaluated once per node, not once per stage (on the benchmark's GP-like residual, 0.13 ms
instead of 0.89 ms per linearisation, measured). Condensing is then dense
linear algebra: S = d x_{1..N} / d u (block lower triangular, S_k = A_{k-1} S_{k-1} plus
B_{k-1}), H = S' Q S + R, grad = S' Q e + R (u - u_ref). The result is the same QP data as the
symbolic linearisation (planners.sqp_solver) up to rounding; its cost does not grow with a
graph per model, and nothing is compiled, so a new residual model is ready at once.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from planners.buffered_function import BufferedFunction
from planners.nmpc_formulation import OBSTACLE_SLOT_SIZE, NmpcFormulation

_POSITION_NAMES = ("pos_n_m", "pos_e_m", "pos_d_m")
_DIST_EPS_M2 = 1e-12  # as planners.nmpc_formulation.obstacle_distance
_RK4_STAGES = (0.5, 0.5, 1.0)


class BatchedLinearisation:
    """(w (n_w,), p (n_p,)) -> the fields of the SQP's linearisation, as NumPy arrays.

    Args:
        formulation: the NLP (model, config, residual).
        xrows: indices into vec(x_1..x_N) of the state-bound rows; x_lo, x_hi: their bounds.
    """

    def __init__(
        self, formulation: NmpcFormulation, xrows: list[int], x_lo: np.ndarray, x_hi: np.ndarray
    ) -> None:
        f = formulation
        model, cfg, residual = f.model, f.config, f.residual
        self._nx, self._nu = model.nx, model.nu
        self._n, self._n_o = cfg.horizon_steps, cfg.n_obstacles
        self._dt = cfg.dt_s
        self._q_all, self._r_all = np.tile(f.q_diag, self._n), np.tile(f.r_diag, self._n)
        self._r_diag = np.diag(self._r_all)
        self._u_min, self._u_max = np.tile(f.u_min, self._n), np.tile(f.u_max, self._n)
        self._xrows, self._x_lo, self._x_hi = np.asarray(xrows, dtype=int), x_lo, x_hi
        self._pos_index = [
            model.state_names.index(c) for c in _POSITION_NAMES if c in model.state_names
        ]
        self._pos_axes = [i for i, c in enumerate(_POSITION_NAMES) if c in model.state_names]
        x, u = ca.SX.sym("x", model.nx), ca.SX.sym("u", model.nu)
        self._batch = None if residual is None else residual.batch
        if self._batch is None:  # all CasADi: the whole interval step and its Jacobians
            x_next = f.step(x, u)
            outs = [x_next, ca.jacobian(x_next, x), ca.jacobian(x_next, u)]
            step = ca.Function("step_jacobians", [x, u], [ca.densify(o) for o in outs])
            self._steps = BufferedFunction(step.map(self._n))
            return
        fx = model.f(x, u)
        z = ca.vec(residual.features(x, u))
        outs = [fx, ca.jacobian(fx, x), ca.jacobian(fx, u), z, ca.jacobian(z, x), ca.jacobian(z, u)]
        self._residual_map = np.asarray(model.residual_map, dtype=float)
        self._history = np.asarray(model.history, dtype=int).reshape(-1, 2).T  # (2, n_history)
        mapped = ca.Function("stage_rates", [x, u], [ca.densify(o) for o in outs]).map(self._n)
        self._rates = BufferedFunction(mapped)

    def _stage(self, xs: np.ndarray, us_t: np.ndarray) -> tuple[np.ndarray, ...]:
        """F (N, nx), dF/dx (N, nx, nx), dF/du (N, nx, nu) at states xs (N, nx)."""
        n, nx, nu = self._n, self._nx, self._nu
        outs = self._rates(xs.T, us_t)
        z = outs[3].T
        nz = z.shape[1]
        g, g_z = self._batch(z)
        b_g = self._residual_map @ g_z  # (N, nx, nz)
        rate = outs[0].T + g @ self._residual_map.T
        d_x = _blocks(outs[1], n, nx, nx) + b_g @ _blocks(outs[4], n, nz, nx)
        d_u = _blocks(outs[2], n, nx, nu) + b_g @ _blocks(outs[5], n, nz, nu)
        return rate, d_x, d_u

    def step_jacobians(self, xs: np.ndarray, us: np.ndarray) -> tuple[np.ndarray, ...]:
        """RK4 step of every node: x_next (N, nx), A (N, nx, nx), B (N, nx, nu)."""
        if self._batch is None:
            n, nx, nu = self._n, self._nx, self._nu
            x_next, a, b = self._steps(xs.T, us.T)
            return x_next.T.copy(), _blocks(a, n, nx, nx), _blocks(b, n, nx, nu)
        h, eye = self._dt, np.eye(self._nx)
        us_t = us.T
        k, j_x, j_u = self._stage(xs, us_t)
        total, a_sum, b_sum = k.copy(), j_x.copy(), j_u.copy()
        for weight, c in zip((2.0, 2.0, 1.0), _RK4_STAGES, strict=True):
            d_x = eye + c * h * j_x  # d x_s / d x
            d_u = c * h * j_u  # d x_s / d u
            k, f_x, f_u = self._stage(xs + c * h * k, us_t)
            j_x, j_u = f_x @ d_x, f_x @ d_u + f_u
            total += weight * k
            a_sum += weight * j_x
            b_sum += weight * j_u
        x_next, a, b = xs + h / 6.0 * total, eye + h / 6.0 * a_sum, h / 6.0 * b_sum
        if self._history.size:  # a history state takes its source's value at the node
            rows, sources = self._history
            x_next[:, rows] = xs[:, sources]
            a[:, rows, :] = 0.0
            a[:, rows, sources] = 1.0
            b[:, rows, :] = 0.0
        return x_next, a, b

    def __call__(self, w: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, ...]:
        """The linearisation's fields in planners.sqp_solver._Linearisation's order."""
        nx, nu, n, n_o = self._nx, self._nu, self._n, self._n_o
        xs = w[: nx * (n + 1)].reshape(n + 1, nx)
        us = w[nx * (n + 1) :].reshape(n, nu)
        i = nx
        x_now = p[:nx]
        x_ref = p[i : i + nx * (n + 1)].reshape(n + 1, nx)
        i += nx * (n + 1)
        u_ref = p[i : i + nu * n].reshape(n, nu)
        i += nu * n
        slots = p[i:].reshape(n_o * n, OBSTACLE_SLOT_SIZE)  # row j * N + k - 1: node k, slot j
        x_next, a, b = self.step_jacobians(xs[:n], us)
        # Node k's [c_k | S_k] (nx, 1 + N nu): c_k the gap carried forward (x_lin_k = x_k + c_k),
        # S_k = d x_lin_k / d u; [c, S]_{k+1} = A_k [c, S]_k + [x_next_k - x_{k+1} | B_k in block k]
        m = np.zeros((n + 1, nx, 1 + n * nu))
        m[0, :, 0] = x_now - xs[0]
        m[1:, :, 0] = x_next - xs[1:]
        nodes = np.arange(n)
        m[1:, :, 1:].reshape(n, nx, n, nu)[nodes, :, nodes, :] = b
        for k in range(n):
            m[k + 1] += a[k] @ m[k]
        c = m[:, :, 0]
        sens = m[1:, :, 1:].reshape(n * nx, n * nu)
        x_lin = (xs[1:] + c[1:]).ravel()
        err = x_lin - x_ref[1:].ravel()
        qs = self._q_all[:, None] * sens
        hess = sens.T @ qs + self._r_diag
        grad = qs.T @ err + (self._r_all * (us - u_ref).ravel())
        u = us.ravel()
        g_h, lba_h = self._obstacle_rows(xs[1:], c[1:], slots)
        return (
            hess,
            grad,
            sens[self._xrows],
            self._x_lo - x_lin[self._xrows],
            self._x_hi - x_lin[self._xrows],
            g_h,
            lba_h,
            self._u_min - u,
            self._u_max - u,
            x_lin,
            sens,
        )

    def _obstacle_rows(
        self, states: np.ndarray, gaps: np.ndarray, slots: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Clearance gradients G_h (N N_o + 1, nx) w.r.t. each row's node's state and lba_h
        (N N_o + 1,), obstacle-major, with the all-zero padding row last (bound -inf)."""
        nx, n, n_o = self._nx, self._n, self._n_o
        g_h = np.zeros((n * n_o + 1, nx))
        lba_h = np.full(n * n_o + 1, -np.inf)
        if not n_o:
            return g_h, lba_h
        pos = np.zeros((n, 3))
        pos[:, self._pos_axes] = states[:, self._pos_index]
        by_node = slots.reshape(n_o, n, OBSTACLE_SLOT_SIZE)  # [j, k - 1]: node k, slot j
        diff = pos - by_node[:, :, 0:3]
        root = np.sqrt(np.sum(by_node[:, :, 3:6] * diff**2, axis=2) + _DIST_EPS_M2)
        clearance = root - by_node[:, :, 6]
        grad_pos = by_node[:, :, 3:6] * diff / root[:, :, None]  # (N_o, N, 3)
        grad_x = g_h[:-1].reshape(n_o, n, nx)
        grad_x[:, :, self._pos_index] = grad_pos[:, :, self._pos_axes]
        lba_h[:-1] = (-clearance - np.sum(grad_x * gaps, axis=2)).ravel()
        return g_h, lba_h


def _blocks(mapped: np.ndarray, n: int, rows: int, cols: int) -> np.ndarray:
    """A mapped Function's (rows, n * cols) output as (n, rows, cols) blocks."""
    return np.asarray(mapped).reshape(rows, n, cols).transpose(1, 0, 2)
