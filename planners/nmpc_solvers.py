"""The two solver paths on one :class:`NmpcFormulation`, chosen by name.

``"fast"``: Gauss-Newton SQP on the condensed QP with DAQP, one iteration per plan by default
(real-time iterations; :mod:`planners.sqp_solver`). ``"ipopt"``: CasADi's IPOPT interface with
its default options on the full multiple-shooting NLP, the reference.
"""

from __future__ import annotations

from typing import Protocol

import casadi as ca
import numpy as np

from planners.nmpc_formulation import SOLVER_NAMES, NmpcFormulation, SolverName
from planners.solver_output import SolverOutput
from planners.sqp_solver import GaussNewtonSqp, SqpOptions


class NlpSolver(Protocol):
    """Solves the formulation's NLP from ``w0`` (n_w,) for parameters p (n_p,).

    ``cold_start`` says that w0 is a guess, not a previous solution.
    """

    def solve(
        self, w0: np.ndarray, p: np.ndarray, time_budget_s: float, cold_start: bool = False
    ) -> SolverOutput: ...


class IpoptSolver:
    """IPOPT (exact Hessian, MUMPS) on the full NLP.

    ``max_iterations`` caps its iterations and ``max_wall_time_s`` its wall time; both are
    fixed when the solver is built (a per-call budget would mean rebuilding it each time).
    """

    def __init__(
        self, formulation: NmpcFormulation, max_iterations: int = 200, max_wall_time_s: float = 1.0
    ) -> None:
        nlp, self._lbg, self._ubg = formulation.nlp()
        self._lbw, self._ubw = formulation.w_bounds()
        opts = {
            "print_time": False,
            "error_on_fail": False,
            "ipopt": {
                "print_level": 0,
                "sb": "yes",
                "max_iter": max_iterations,
                "max_wall_time": max(max_wall_time_s, 1e-9),
                "warm_start_init_point": "no",
            },
        }
        self._solver = ca.nlpsol("nmpc_ipopt", "ipopt", nlp, opts)

    def solve(
        self, w0: np.ndarray, p: np.ndarray, time_budget_s: float, cold_start: bool = False
    ) -> SolverOutput:
        """Solve from ``w0``; ``time_budget_s`` and ``cold_start`` do not change IPOPT."""
        sol = self._solver(x0=w0, p=p, lbx=self._lbw, ubx=self._ubw, lbg=self._lbg, ubg=self._ubg)
        stats = self._solver.stats()
        w = np.asarray(sol["x"]).ravel()
        ok = bool(stats["success"])
        return SolverOutput(w, ok, "" if ok else str(stats["return_status"]), stats["iter_count"])


def make_solver(
    name: SolverName,
    formulation: NmpcFormulation,
    max_iterations: int | None = None,
    compile_functions: bool = False,
    max_wall_time_s: float = 1.0,
) -> NlpSolver:
    """Build a solver path by name; a bad name raises ValueError listing the valid ones.

    ``compile_functions`` compiles the fast path's symbolic linearisation to C (cached per
    machine; the default linearisation, compiled per shape or NumPy, ignores it);
    ``max_wall_time_s`` limits each IPOPT solve (the fast path checks its budget per call).
    """
    if name == "fast":
        opts = SqpOptions(compile=compile_functions)
        if max_iterations is not None:
            opts = SqpOptions(max_iterations=max_iterations, compile=compile_functions)
        return GaussNewtonSqp(formulation, opts)
    if name == "ipopt":
        iterations = 200 if max_iterations is None else max_iterations
        return IpoptSolver(formulation, iterations, max_wall_time_s)
    raise ValueError(f"unknown NMPC solver {name!r}; choose one of {', '.join(SOLVER_NAMES)}")
