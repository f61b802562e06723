"""The fast path's Gauss-Newton linearisation with its condensing in one compiled C routine.

The same QP data as :class:`planners.batched_linearisation.BatchedLinearisation` (the fields of
planners.sqp_solver._Linearisation). One CasADi Function of (w, p, theta), compiled to C
(planners.compiled_function), replaces the chain of NumPy operations:

- the RK4 interval step with its Jacobians A_k, B_k, mapped over the N nodes (a loop in C);
- condensing, unrolled over the nodes: c_{k+1} = A_k c_k + x_next_k - x_{k+1} (the gap carried
  forward, c_0 = x_now - x_0), L_{k+1} = [A_k L_k, B_k] (d x_{k+1} / d u_0..u_k), S the block
  lower triangular stack of the L_k, the cost's error e = [x_lin - x_ref, u - u_ref];
- the obstacle rows: each slot's clearance and its gradient, mapped over the slots;
- the bounds relative to the iterate.

H = S' Q S + R and g = S' Q e_x + R e_u are then two dense products in NumPy (BLAS, 25 us on
the benchmark problem; in the generated C, S' Q S on S's sparsity took 125 us, and block by
block it compiled for 11 s instead of 1.2 s, measured).

``theta`` holds the numbers: the interval step's constants (the nominal model's, the step
length, the learned residual's data: planners.constants_as_inputs), then the input and state
bounds. The C code therefore depends on the shapes only (nx, nu, N, N_o, the step's graph), and
a new model of the same shape reuses the compiled library (cached per machine by source hash)
at once. Without a C compiler :func:`compiled_linearisation` returns None and the planner uses
the NumPy path.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from planners.buffered_function import BufferedFunction
from planners.compiled_function import compiled
from planners.constants_as_inputs import constants_as_input
from planners.nmpc_formulation import OBSTACLE_SLOT_SIZE, NmpcFormulation


class CompiledLinearisation:
    """(w (n_w,), p (n_p,)) -> the fields of the SQP's linearisation as NumPy arrays (buffers
    reused by the next call).

    Args:
        fn: the compiled Function of (w, p, theta) (see :func:`linearisation_function`).
        theta: its numbers (n_theta,).
        q_all (nx N,), r_all (nu N,): the cost weights of x_1..x_N and u_0..u_{N-1}.
    """

    def __init__(
        self, fn: ca.Function, theta: np.ndarray, q_all: np.ndarray, r_all: np.ndarray
    ) -> None:
        self._fn = BufferedFunction(fn)
        w_in, p_in, theta_in = self._fn.inputs
        self._w, self._p = w_in[:, 0], p_in[:, 0]
        theta_in[:, 0] = theta
        # 1-D views of the vector outputs (the matrices are used as they are)
        self._outputs = [out[:, 0] if out.shape[1] == 1 else out for out in self._fn.outputs]
        n_x, n_u = q_all.size, r_all.size
        self._q, self._r = q_all[:, None], r_all
        self._qs = np.zeros((n_x, n_u))
        self._hess, self._grad = np.zeros((n_u, n_u)), np.zeros(n_u)
        self._hess_diag = self._hess.reshape(-1)[:: n_u + 1]  # a view: H's diagonal

    def __call__(self, w: np.ndarray, p: np.ndarray) -> list[np.ndarray]:
        """The linearisation's fields in planners.sqp_solver._Linearisation's order."""
        self._w[:] = w
        self._p[:] = p
        self._fn.evaluate()
        a_x, lba_x, uba_x, g_h, lba_h, lbx, ubx, x_lin, sens, err = self._outputs
        n_x = self._qs.shape[0]
        np.multiply(self._q, sens, out=self._qs)
        np.matmul(sens.T, self._qs, out=self._hess)
        self._hess_diag += self._r
        np.matmul(err[:n_x], self._qs, out=self._grad)
        self._grad += self._r * err[n_x:]
        return [self._hess, self._grad, a_x, lba_x, uba_x, g_h, lba_h, lbx, ubx, x_lin, sens]


def compiled_linearisation(
    formulation: NmpcFormulation, xrows: list[int], x_lo: np.ndarray, x_hi: np.ndarray
) -> CompiledLinearisation | None:
    """The compiled linearisation of ``formulation`` (state-bound rows ``xrows`` of vec(x_1..x_N)
    with bounds x_lo, x_hi), or None when it cannot be compiled (no C compiler)."""
    fn, theta = linearisation_function(formulation, xrows, x_lo, x_hi)
    built = compiled(fn)
    if built is fn:
        return None
    f = formulation
    n = f.config.horizon_steps
    return CompiledLinearisation(built, theta, np.tile(f.q_diag, n), np.tile(f.r_diag, n))


def linearisation_function(
    formulation: NmpcFormulation, xrows: list[int], x_lo: np.ndarray, x_hi: np.ndarray
) -> tuple[ca.Function, np.ndarray]:
    """(the MX Function (w, p, theta) -> A_x, lba_x, uba_x, G_h, lba_h, lbx, ubx, x_lin, S,
    e (all dense; as planners.sqp_solver._Linearisation, e the cost's error (nx N + nu N)),
    theta's values)."""
    f = formulation
    nx, nu, n, n_o = f.model.nx, f.model.nu, f.config.horizon_steps, f.config.n_obstacles
    step, step_theta = constants_as_input(f.step)
    x, u, th = ca.SX.sym("x", nx), ca.SX.sym("u", nu), ca.SX.sym("theta", step_theta.size)
    x_next = step(x, u, th)
    jac = ca.Function(
        "step_jacobians",
        [x, u, th],
        [ca.densify(o) for o in (x_next, ca.jacobian(x_next, x), ca.jacobian(x_next, u))],
    )
    n_rows = len(xrows)
    sizes = (step_theta.size, nu * n, nu * n, n_rows, n_rows)
    numbers = np.concatenate([step_theta, np.tile(f.u_min, n), np.tile(f.u_max, n), x_lo, x_hi])
    w, p, theta = ca.MX.sym("w", f.n_w), ca.MX.sym("p", f.n_p), ca.MX.sym("theta", numbers.size)
    th_step, u_min, u_max, lo, hi = ca.vertsplit(theta, list(np.cumsum((0, *sizes))))
    xs = ca.reshape(w[: nx * (n + 1)], nx, n + 1)
    us = ca.reshape(w[nx * (n + 1) :], nu, n)
    x_now, x_ref, u_ref, slots = f.split_parameters(p)
    x_nexts, a_all, b_all = jac.map(n)(xs[:, :n], us, th_step)
    gaps = [x_now - xs[:, 0]]
    lower = [ca.MX(nx, 0)]  # L_k = d x_k / d (u_0..u_{k-1}), (nx, k nu)
    for k in range(n):
        a_k = a_all[:, k * nx : (k + 1) * nx]
        gaps.append(a_k @ gaps[k] + x_nexts[:, k] - xs[:, k + 1])
        lower.append(ca.horzcat(a_k @ lower[k], b_all[:, k * nu : (k + 1) * nu]))
    sens = ca.vertcat(*[ca.horzcat(lower[k], ca.MX(nx, (n - k) * nu)) for k in range(1, n + 1)])
    c = ca.horzcat(*gaps)  # (nx, N + 1)
    x_lin = ca.vec(xs[:, 1:] + c[:, 1:])
    u = ca.vec(us)
    err = ca.vertcat(x_lin - ca.vec(x_ref[:, 1:]), u - ca.vec(u_ref))
    g_h, lba_h = _obstacle_rows(f, xs[:, 1:], c[:, 1:], slots)
    outs = [
        sens[xrows, :],
        lo - x_lin[xrows],
        hi - x_lin[xrows],
        g_h,
        lba_h,
        u_min - u,
        u_max - u,
        x_lin,
        sens,
        err,
    ]
    names = ["a_x", "lba_x", "uba_x", "g_h", "lba_h", "lbx", "ubx", "x_lin", "sens", "err"]
    fn = ca.Function(
        f"gn_sqp_linearisation_{nx}x{nu}x{n}x{n_o}",
        [w, p, theta],
        [ca.densify(o) for o in outs],
        ["w", "p", "theta"],
        names,
    )
    return fn, numbers


def _obstacle_rows(
    f: NmpcFormulation, states: ca.MX, gaps: ca.MX, slots: ca.MX
) -> tuple[ca.MX, ca.MX]:
    """G_h (N N_o + 1, nx): row j N + k - 1 is slot j's clearance gradient w.r.t. x_k; lba_h
    (N N_o + 1): minus the linearised clearance; the last row is the all-zero padding row
    (bound -inf)."""
    nx, n, n_o = f.model.nx, f.config.horizon_steps, f.config.n_obstacles
    if not n_o:
        return ca.MX(1, nx), ca.MX(-ca.inf)
    x, gap, slot = ca.SX.sym("x", nx), ca.SX.sym("gap", nx), ca.SX.sym("slot", OBSTACLE_SLOT_SIZE)
    h = f.clearance(x, slot)
    grad = ca.jacobian(h, x)
    row = ca.Function("clearance_row", [x, gap, slot], [grad.T, -h - grad @ gap])
    grads, lba = row.map(n * n_o)(ca.repmat(states, 1, n_o), ca.repmat(gaps, 1, n_o), slots)
    return ca.vertcat(grads.T, ca.MX(1, nx)), ca.vertcat(lba.T, -ca.inf)
