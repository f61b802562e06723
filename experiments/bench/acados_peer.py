"""acados (SQP_RTI + HPIPM) on one :class:`NmpcFormulation`: the field's reference solver, as
[Torrente21]'s data-driven MPC uses it, for `bench --only nmpc` to measure our fast path against.

Optional: it needs the ``comma-deps-acados`` package (acados' libraries, its code generator and
Python template; ``make acados`` installs it and then restores the full CasADi it overwrites).
Without it :func:`acados_unavailable` says why and the bench reports NaN.

The OCP is the formulation's, stage by stage: discrete dynamics x+ = f_d(x, u) (the same RK4
step, residual included, as CasADi expressions: acados generates C for them and compiles one
solver per formulation), linear least-squares cost with weights diag(Q, R) and references
(x_ref_k, u_ref_k), input bounds, x_0 = x_now, and the obstacle clearances as nonlinear
constraints h >= 0 on every stage, softened with the same exact L1 + small L2 penalty as our
fast path. Each node's obstacle slots are its stage's parameters, so one solver serves every
problem.
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import os
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import casadi as ca
import numpy as np

from planners.nmpc_formulation import OBSTACLE_SLOT_SIZE, UNUSED_SLOT, NmpcFormulation
from planners.solver_output import SolverOutput

COLD_START_ITERATIONS = 10
_SLACK_L1 = 1e5
_SLACK_L2 = 1.0
_NO_UPPER = 1e4  # [m]


def acados_unavailable() -> str:
    """Why acados cannot run here ("" when it can)."""
    try:
        import acados  # noqa: F401
        from acados.acados_template import AcadosOcp  # noqa: F401
    except ImportError as exc:
        return f"acados is not installed ({exc}); run `make acados`"
    if not ca.has_nlpsol("ipopt"):
        return "the slim CasADi of comma-deps-acados replaced the full one; run `make acados`"
    return ""


@contextlib.contextmanager
def c_stdout_to_stderr() -> Iterator[None]:
    """Inside, what C code writes to the standard output goes to the standard error: acados
    prints a line there for every QP its HPIPM fails ("SQP_RTI: QP solver returned error
    status 3"), which would break `bench --json`'s output."""
    sys.stdout.flush()
    libc = ctypes.CDLL(None)
    libc.fflush(None)
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        libc.fflush(None)
        os.dup2(saved, 1)
        os.close(saved)


def _prepare_environment() -> None:
    """Point acados' template at the package's install tree and load its libraries globally,
    so that the generated solver library finds them without LD_LIBRARY_PATH."""
    import acados

    os.environ.setdefault("ACADOS_SOURCE_DIR", acados.DIR)
    os.environ.setdefault("ACADOS_PYTHON_INTERFACE_PATH", acados.TEMPLATE_DIR)
    for lib in ("libblasfeo.so", "libhpipm.so", "libqpOASES_e.so", "libacados.so"):
        path = Path(acados.LIB_DIR) / lib
        if path.exists():
            ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)


class AcadosSolver:
    """SQP_RTI + HPIPM (partial condensing) on the formulation; the ``NlpSolver`` contract.

    One RTI iteration per solve from the given warm start (``COLD_START_ITERATIONS`` on a cold
    start), as our fast path. Building generates and compiles the solver in ``build_dir``
    (a temporary folder by default) and takes about a second or two.

    Attributes:
        last_solve_s: acados' own time (``time_tot``) of the last solve [s]: the C solver
            alone, without this class' per-stage Python ``set``/``get`` calls.
    """

    def __init__(self, formulation: NmpcFormulation, build_dir: Path | None = None) -> None:
        from acados.acados_template import AcadosModel, AcadosOcp, AcadosOcpSolver

        _prepare_environment()
        f = formulation
        nx, nu, n = f.model.nx, f.model.nu, f.config.horizon_steps
        n_o = f.config.n_obstacles
        self._f, self._nx, self._nu, self._n = f, nx, nu, n
        self.last_solve_s = float("nan")
        self._healthy = True
        x = ca.SX.sym("x", nx)
        u = ca.SX.sym("u", nu)
        slots = ca.SX.sym("slots", OBSTACLE_SLOT_SIZE * n_o)
        model = AcadosModel()
        model.name = "nmpc_peer"
        model.x, model.u, model.p = x, u, slots
        model.disc_dyn_expr = f.step(x, u)
        ocp = AcadosOcp()
        ocp.model = model
        ocp.dims.N = n
        ny = nx + nu
        ocp.cost.cost_type = "LINEAR_LS"
        ocp.cost.cost_type_e = "LINEAR_LS"
        ocp.cost.W = np.diag(np.concatenate([f.q_diag, f.r_diag]))
        ocp.cost.W_e = np.diag(f.q_diag)
        ocp.cost.Vx = np.vstack([np.eye(nx), np.zeros((nu, nx))])
        ocp.cost.Vu = np.vstack([np.zeros((nx, nu)), np.eye(nu)])
        ocp.cost.Vx_e = np.eye(nx)
        ocp.cost.yref = np.zeros(ny)
        ocp.cost.yref_e = np.zeros(nx)
        ocp.constraints.x0 = np.zeros(nx)
        ocp.constraints.idxbu = np.arange(nu)
        ocp.constraints.lbu = f.u_min
        ocp.constraints.ubu = f.u_max
        ocp.parameter_values = np.zeros(OBSTACLE_SLOT_SIZE * n_o)
        if n_o:
            clear = ca.vertcat(
                *[
                    f.clearance(x, slots[OBSTACLE_SLOT_SIZE * j : OBSTACLE_SLOT_SIZE * (j + 1)])
                    for j in range(n_o)
                ]
            )
            model.con_h_expr = clear
            model.con_h_expr_e = clear
            for suffix in ("", "_e"):
                setattr(ocp.constraints, "lh" + suffix, np.zeros(n_o))
                setattr(ocp.constraints, "uh" + suffix, np.full(n_o, _NO_UPPER))
                setattr(ocp.constraints, "idxsh" + suffix, np.arange(n_o))
                # The upper bound (far beyond any clearance) is softened too, with the same
                # weights: a free upper slack would leave the QP's slacks non-unique.
                for name, value in (
                    ("zl", _SLACK_L1),
                    ("zu", _SLACK_L1),
                    ("Zl", _SLACK_L2),
                    ("Zu", _SLACK_L2),
                ):
                    setattr(ocp.cost, name + suffix, np.full(n_o, value))
        opts = ocp.solver_options
        # acados weighs each stage cost by its time step; with discrete dynamics the step only
        # does that, so a unit step keeps the formulation's cost (stage and terminal alike).
        opts.tf = float(n)
        opts.integrator_type = "DISCRETE"
        opts.nlp_solver_type = "SQP_RTI"
        opts.hessian_approx = "GAUSS_NEWTON"
        opts.qp_solver = "PARTIAL_CONDENSING_HPIPM"
        opts.print_level = 0
        opts.qp_solver_iter_max = 100
        opts.qp_solver_cond_N = max(1, n // 4)
        opts.qp_solver_warm_start = 1
        self._tmp = None
        if build_dir is None:
            self._tmp = tempfile.TemporaryDirectory(prefix="acados_peer_")
            build_dir = Path(self._tmp.name)
        ocp.code_export_directory = str(build_dir / "c_generated_code")
        with contextlib.redirect_stdout(io.StringIO()):
            self._solver = AcadosOcpSolver(
                ocp, json_file=str(build_dir / "nmpc_peer.json"), verbose=False
            )

    def solve(
        self, w0: np.ndarray, p: np.ndarray, time_budget_s: float, cold_start: bool = False
    ) -> SolverOutput:
        """One RTI iteration from ``w0`` (more on a cold start); ``time_budget_s`` unused."""
        f, s, n = self._f, self._solver, self._n
        x_now, x_ref, u_ref, slots = (np.asarray(a) for a in f.split_parameters(ca.DM(p)))
        states, inputs = f.split_w(np.asarray(w0, dtype=float))
        if cold_start or not self._healthy:
            s.reset()  # a failed QP leaves NaNs in acados' memory
        n_o = f.config.n_obstacles
        # stage k's parameters: node k's slots (columns j * N + k - 1); stage 0 (x_0 fixed)
        # has no obstacles
        unused = np.tile(UNUSED_SLOT, n_o)
        p_stage = [unused] + [np.ravel(slots[:, k - 1 :: n], order="F") for k in range(1, n + 1)]
        for k in range(n):
            s.set(k, "yref", np.concatenate([x_ref[:, k], u_ref[:, k]]))
            s.set(k, "p", p_stage[k])
            s.set(k, "x", states[k])
            s.set(k, "u", inputs[k])
        s.set(n, "yref", x_ref[:, n])
        s.set(n, "p", p_stage[n])
        s.set(n, "x", states[n])
        s.set(0, "lbx", x_now.ravel())
        s.set(0, "ubx", x_now.ravel())
        status = 0
        self.last_solve_s = 0.0
        for _ in range(COLD_START_ITERATIONS if cold_start else 1):
            status = s.solve()
            self.last_solve_s += float(np.ravel(s.get_stats("time_tot"))[0])
            if status not in (0, 2):
                break
        out_x = np.vstack([s.get(k, "x") for k in range(n + 1)])
        out_u = np.vstack([s.get(k, "u") for k in range(n)])
        ok = status in (0, 2) and bool(np.all(np.isfinite(out_u)))  # 2: iteration limit
        self._healthy = ok
        return SolverOutput(f.pack_w(out_x, out_u), ok, "" if ok else f"acados status {status}", 1)
