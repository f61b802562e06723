"""Fast solver path: Gauss-Newton SQP on the condensed multiple-shooting QP.

Each iteration linearises the dynamics and obstacle constraints at the current iterate (w, as
in multiple shooting: states and inputs, gaps allowed), eliminates the state deviations
(condensing, which also embeds x_0 = x_now), and solves the dense QP in the input steps with
DAQP, a dual active-set solver that is fast on small dense QPs (planners.condensed_qp); the
obstacle rows share one penalised slack so that a QP linearised at a poor iterate stays
feasible. The Hessian is the exact Hessian of the least-squares cost (Gauss-Newton: constraint
curvature is dropped). With one iteration per control step and a shifted warm start this is the
real-time iteration scheme.

The linearisation and its condensing are by default one compiled C routine whose numbers (the
model's constants, the learned residual's data) are inputs, so one build per machine serves
every model of the same shape (:mod:`planners.compiled_linearisation`); without a C compiler,
for a residual with a batched form (a learned GP), or with ``linearisation="batched"``, they
are evaluated node-parallel in NumPy
(:mod:`planners.batched_linearisation`: the RK4 step's Jacobians through the chain rule, the
residual's batched form, dense condensing); ``linearisation="symbolic"`` builds it as a single
CasADi Function over the whole horizon instead (the path the planner used before; with
``compile=True`` compiled to C at first use, see :mod:`planners.compiled_function`), kept as
the reference the batched one is checked against.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Literal, NamedTuple

import casadi as ca
import numpy as np
from threadpoolctl import ThreadpoolController

from planners.batched_linearisation import BatchedLinearisation
from planners.compiled_function import compiled
from planners.compiled_linearisation import compiled_linearisation
from planners.condensed_qp import CondensedQp
from planners.nmpc_formulation import NmpcFormulation
from planners.solver_output import SolverOutput

_BUCKET = 8  # obstacle rows come in blocks of this many (padded), one QP size per block


class _Linearisation(NamedTuple):
    """The QP data of one Gauss-Newton SQP iteration at the current iterate (NumPy arrays).

    hess, grad: Gauss-Newton Hessian and gradient of the cost in the inputs; a_x, lba_x, uba_x:
    state-bound rows (sensitivity and bounds relative to the linearised trajectory); g_h, lba_h:
    obstacle rows (N N_o + 1, nx) and (N N_o + 1,), obstacle-major (row j N + k - 1: slot j at
    node k): the clearance's gradient w.r.t. x_k (the row's only nonzero block: the QP row is
    g_h S_k, S_k node k's rows of sens) and its lower bound, a padding row last (zero, -inf);
    lbx, ubx: input bounds relative to the iterate; x_lin: the trajectory the inputs produce;
    sens: d x_lin / d u.
    """

    hess: Any
    grad: Any
    a_x: Any
    lba_x: Any
    uba_x: Any
    g_h: Any
    lba_h: Any
    lbx: Any
    ubx: Any
    x_lin: Any
    sens: Any


LINEARISATIONS: tuple[str, ...] = ("compiled", "batched", "symbolic")
_BLAS: list[list] = []  # the BLAS libraries' controllers, found at the first solve (a scan)


@dataclass(frozen=True)
class SqpOptions:
    """Settings of the Gauss-Newton SQP.

    Attributes:
        max_iterations: SQP iterations per solve; 1 (default) is the real-time iteration
            scheme: with the shifted warm start the iterate converges over control steps.
        cold_start_iterations: iterations when there is no previous solution to start from
            (first plan, after a failure), at least ``max_iterations``.
        step_tol: stop when the largest input step and dynamics gap are below this.
        linearisation: "compiled" (one C routine per shape, planners.compiled_linearisation;
            "batched" when it cannot be compiled or the residual has a batched form: a learned
            GP's step compiles for 14 s, over the 10 s a new model may take to be ready to
            fly, measured), "batched" (NumPy, node-parallel;
            planners.batched_linearisation) or "symbolic" (one CasADi Function over the
            horizon, the reference).
        compile: compile the symbolic linearisation to C (needs a C compiler; falls back to
            the CasADi virtual machine without one). Measured on the benchmark problem: about
            15 % faster per plan, but the first build of each formulation (each new residual
            model) takes a minute or more, so it is off by default. The compiled and batched
            linearisations ignore it.
        qp_feasibility_tol: a QP solution violating its constraints by more is a failure.
        screen_distance_m: obstacle rows whose linearised clearance exceeds this [m] are left
            out of the QP (they cannot become active within one step of a converging SQP).
        max_obstacle_rows: at most this many obstacle rows (the smallest clearances) per QP.
        slack_weight_linear, slack_weight_quadratic: cost rho s + eps s^2 / 2 of the one
            slack s >= 0 [m] shared by all obstacle rows, which keeps every QP feasible (an
            exact penalty: s stays 0 whenever the linearised constraints can be met). The
            planner rejects a plan whose simulation still violates a constraint.
    """

    max_iterations: int = 1
    cold_start_iterations: int = 10
    linearisation: Literal["compiled", "batched", "symbolic"] = "compiled"
    step_tol: float = 1e-6
    compile: bool = False
    qp_feasibility_tol: float = 1e-6
    screen_distance_m: float = 1.0
    max_obstacle_rows: int = 24
    slack_weight_linear: float = 1e5
    slack_weight_quadratic: float = 1.0

    def __post_init__(self) -> None:
        if self.max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {self.max_iterations}")
        if self.linearisation not in LINEARISATIONS:
            raise ValueError(
                f"unknown linearisation {self.linearisation!r}; choose one of "
                f"{', '.join(LINEARISATIONS)}"
            )


class GaussNewtonSqp:
    """Gauss-Newton SQP with condensing and DAQP; see the module docstring."""

    def __init__(self, formulation: NmpcFormulation, options: SqpOptions | None = None) -> None:
        self.formulation = formulation
        self.options = options or SqpOptions()
        model, cfg = formulation.model, formulation.config
        nx, nu, n = model.nx, model.nu, cfg.horizon_steps
        self._nx, self._nu, self._n = nx, nu, n
        # Rows of state bounds that are finite somewhere: only those enter the QP.
        lo = np.tile(formulation.x_min, n)
        hi = np.tile(formulation.x_max, n)
        self._xrows = [int(i) for i in np.flatnonzero(np.isfinite(lo) | np.isfinite(hi))]
        self._x_lo, self._x_hi = lo[self._xrows], hi[self._xrows]
        kind = self.options.linearisation
        rows = (formulation, self._xrows, self._x_lo, self._x_hi)
        residual = formulation.residual
        compile_it = kind == "compiled" and (residual is None or residual.batch is None)
        fast = compiled_linearisation(*rows) if compile_it else None
        if fast is not None:
            self._lin = fast
        elif kind in ("compiled", "batched"):
            self._lin = BatchedLinearisation(*rows)
        else:
            lin = self._build_linearisation()
            lin = compiled(lin) if self.options.compile else lin
            self._lin = lambda w, p: [_numpy(out) for out in lin(w, p)]
        # One QP per size of the obstacle-row block (rows padded up to the bucket).
        cap = min(self.options.max_obstacle_rows, n * cfg.n_obstacles)
        self._buckets = sorted({min(cap, b) for b in range(0, cap + _BUCKET, _BUCKET)})
        n_u, opts = nu * n, self.options
        self._qps = {
            b: CondensedQp(
                n_u, len(self._xrows), b, opts.slack_weight_linear, opts.slack_weight_quadratic
            )
            for b in self._buckets
        }
        # each count of near rows' bucket, and each bucket's row indices (filled per iteration)
        self._bucket_of = [next(b for b in self._buckets if b >= k) for k in range(cap + 1)]
        self._rows = {b: np.zeros(b, dtype=np.intp) for b in self._buckets}
        self._pad_row = n * cfg.n_obstacles  # index of the all-zero row lin appends
        # Each obstacle row's node's rows of sens (the padding row's: node 1's, times zero).
        node = np.append(np.tile(np.arange(n), cfg.n_obstacles), 0)
        self._row_states = node[:, None] * nx + np.arange(nx)  # (N N_o + 1, nx)

    def _build_linearisation(self) -> ca.Function:
        """(w, p) -> the condensed QP at w, built block-wise in O(N^2) (no dense products).

        Outputs: H (nu*N, nu*N), g (nu*N), A_x (state-bound rows, nu*N), lba_x, uba_x,
        G_h (N*N_o + 1, nx): each obstacle row's clearance gradient w.r.t. its node's state, so
        its QP row is G_h S_k; lba_h (N*N_o + 1): minus the linearised clearance, obstacle-major
        (the last row is all zero with bound -inf, used to pad row blocks);
        lbx, ubx (nu*N; input step bounds), x_lin (nx*N): states x_1..x_N predicted with zero
        input step, S (nx*N, nu*N): their sensitivity to the input step.
        """
        f = self.formulation
        nx, nu, n, n_o = self._nx, self._nu, self._n, f.config.n_obstacles
        w = ca.SX.sym("w", f.n_w)
        p = ca.SX.sym("p", f.n_p)
        xs = ca.reshape(w[: nx * (n + 1)], nx, n + 1)
        us = ca.reshape(w[nx * (n + 1) :], nu, n)
        x_now, x_ref, u_ref, slots = f.split_parameters(p)
        xk, uk = ca.SX.sym("xk", nx), ca.SX.sym("uk", nu)
        fk = f.step(xk, uk)
        jac = ca.Function(
            "step_jacobians", [xk, uk], [fk, ca.jacobian(fk, xk), ca.jacobian(fk, uk)]
        )
        q, r = ca.diag(ca.DM(f.q_diag)), ca.diag(ca.DM(f.r_diag))
        a_blk, b_blk, c_blk = [], [], [x_now - xs[:, 0]]
        for k in range(n):
            fv, a, b = jac(xs[:, k], us[:, k])
            a_blk.append(a)
            b_blk.append(b)
            c_blk.append(fv - xs[:, k + 1] + a @ c_blk[k])
        # s_blk[k][j] = d x_k / d u_j for j < k (k = 1..N).
        s_blk: list[list[ca.SX]] = [[]]
        for k in range(n):
            s_blk.append([a_blk[k] @ s for s in s_blk[k]] + [b_blk[k]])
        zero = ca.SX(nx, nu)
        sens = ca.blockcat([s_blk[k] + [zero] * (n - k) for k in range(1, n + 1)])
        x_lin = ca.vertcat(*[xs[:, k] + c_blk[k] for k in range(1, n + 1)])
        err = [xs[:, k] + c_blk[k] - x_ref[:, k] for k in range(n + 1)]
        # Backward recursions: mu_k = Q e_k + A_k' mu_{k+1}, W_k = Q + A_k' W_{k+1} A_k.
        mu, wk = [None] * (n + 1), [None] * (n + 1)
        mu[n], wk[n] = q @ err[n], q
        for k in range(n - 1, 0, -1):
            mu[k] = q @ err[k] + a_blk[k].T @ mu[k + 1]
            wk[k] = q + a_blk[k].T @ wk[k + 1] @ a_blk[k]
        grad = ca.vertcat(
            *[b_blk[j].T @ mu[j + 1] + r @ (us[:, j] - u_ref[:, j]) for j in range(n)]
        )
        h_blk = [[ca.SX(nu, nu) for _ in range(n)] for _ in range(n)]
        for j in range(n):
            v = wk[j + 1] @ b_blk[j]
            h_blk[j][j] = b_blk[j].T @ v + r
            for i in range(j - 1, -1, -1):
                v = a_blk[i + 1].T @ v
                h_blk[i][j] = b_blk[i].T @ v
                h_blk[j][i] = h_blk[i][j].T
        hess = ca.blockcat(h_blk)
        grads_h, lb_h = [], []
        if n_o:
            slot = ca.SX.sym("slot", slots.size1())
            hk = f.clearance(xk, slot)
            hjac = ca.Function("clearance_jacobian", [xk, slot], [hk, ca.jacobian(hk, xk)])
            for j in range(n_o):
                for k in range(1, n + 1):
                    hv, gx = hjac(xs[:, k], slots[:, j * n + k - 1])
                    grads_h.append(gx)
                    lb_h.append(-hv - gx @ c_blk[k])
        u = ca.vec(us)
        outs = _Linearisation(
            hess=hess,
            grad=grad,
            a_x=sens[self._xrows, :],
            lba_x=self._x_lo - x_lin[self._xrows],
            uba_x=self._x_hi - x_lin[self._xrows],
            g_h=ca.vertcat(*grads_h, ca.SX(1, nx)),
            lba_h=ca.vertcat(*lb_h, -ca.inf),
            lbx=ca.DM(np.tile(f.u_min, n)) - u,
            ubx=ca.DM(np.tile(f.u_max, n)) - u,
            x_lin=x_lin,
            sens=sens,
        )
        dense = [ca.densify(out) for out in outs]
        return ca.Function(
            "gn_sqp_linearisation", [w, p], dense, ["w", "p"], list(_Linearisation._fields)
        )

    def solve(
        self, w0: np.ndarray, p: np.ndarray, time_budget_s: float, cold_start: bool = False
    ) -> SolverOutput:
        """Run up to ``max_iterations`` SQP iterations from ``w0`` (n_w,) with parameters p.

        ``cold_start`` (w0 is not a previous solution) allows ``cold_start_iterations``.
        Stops early when converged, or when one more iteration, as long as the slowest so far,
        would end after ``time_budget_s`` [s]: a cold start on a busy computer then returns
        the iterate it has (each iteration's QP is feasible; the planner checks the plan)
        instead of overrunning the budget by its last iteration.
        """
        if not _BLAS:
            _BLAS.append(ThreadpoolController().select(user_api="blas").lib_controllers)
        # The products are small: BLAS threads would only wait for a core (on a loaded
        # computer, 3x the solve's CPU time, measured); one thread, only inside the solve.
        # (Set on the libraries directly: threadpoolctl's limit() costs 45 us a call.)
        threaded = [(lib, n) for lib in _BLAS[0] if (n := lib.num_threads) != 1]
        for lib, _ in threaded:
            lib.set_num_threads(1)
        try:
            return self._solve(w0, p, time_budget_s, cold_start)
        finally:
            for lib, n in threaded:
                lib.set_num_threads(n)

    def _solve(
        self, w0: np.ndarray, p: np.ndarray, time_budget_s: float, cold_start: bool
    ) -> SolverOutput:
        start = time.perf_counter()
        slowest_s = 0.0
        opts = self.options
        w = np.asarray(w0, dtype=float)
        p = np.asarray(p, dtype=float)
        nx = self._nx
        split = nx * (self._n + 1)
        x_now = p[:nx]
        iterations = max(opts.max_iterations, opts.cold_start_iterations if cold_start else 1)
        for it in range(1, iterations + 1):
            iteration_start = time.perf_counter()
            lin = _Linearisation(*self._lin(w, p))
            # Only obstacle rows whose linearised clearance (-lba_h) is small can become active.
            near = np.flatnonzero(lin.lba_h[: self._pad_row] > -opts.screen_distance_m)
            if near.size > self._buckets[-1]:
                near = near[np.argsort(-lin.lba_h[near])[: self._buckets[-1]]]
            bucket = self._bucket_of[near.size]
            rows = self._rows[bucket]
            rows[: near.size] = near
            rows[near.size :] = self._pad_row
            a_h = np.matmul(lin.g_h[rows, None, :], lin.sens[self._row_states[rows]])[:, 0, :]
            du, violation = self._qps[bucket].solve(
                lin.hess,
                lin.grad,
                lin.a_x,
                lin.lba_x,
                lin.uba_x,
                a_h,
                lin.lba_h[rows],
                lin.lbx,
                lin.ubx,
            )
            gap = np.abs(lin.x_lin - w[nx:split]).max()
            step = float(np.maximum(np.abs(du).max(), gap))  # NaN in either stays NaN
            if not violation <= opts.qp_feasibility_tol:
                reason = f"QP failed (constraint violation {violation:.3g})"
                return SolverOutput(w, False, reason, it)
            if not np.isfinite(step):
                reason = "non-finite step (NaN or inf in the linearisation at the iterate)"
                return SolverOutput(w, False, reason, it)
            w = np.concatenate([x_now, lin.x_lin + lin.sens @ du, w[split:] + du])
            now = time.perf_counter()
            slowest_s = max(slowest_s, now - iteration_start)
            if step < opts.step_tol or now - start + slowest_s > time_budget_s:
                break
        return SolverOutput(w, True, "", it)


def _numpy(value: ca.DM) -> np.ndarray:
    """A CasADi matrix as a dense NumPy array; a column vector as a 1-D array."""
    arr = np.asarray(value.full() if isinstance(value, ca.DM) else value, dtype=float)
    return arr.ravel() if arr.ndim == 2 and arr.shape[1] == 1 else arr
