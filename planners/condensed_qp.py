"""The fast path's condensed QP of one SQP iteration: assembled in NumPy, solved by DAQP.

In the input step du (nu N) and one slack s >= 0 [m] shared by the obstacle rows::

    min  du' H du / 2 + g' du + eps s^2 / 2 + rho s
    s.t. lba_x <= A_x du <= uba_x            (state-bound rows)
         A_h du + s >= lba_h                 (obstacle rows, A_h = G_h S)
         lbx <= du <= ubx,  s >= 0

DAQP (a dual active-set solver, fast on small dense QPs) is called through CasADi's conic
interface on buffers bound once (planners.buffered_function): the products and copies around
it are NumPy's, not the CasADi virtual machine's (on the benchmark problem, 80 inputs and 24
obstacle rows, 0.19 ms of DAQP in a step that took 0.30 ms on MX, measured).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from planners.buffered_function import BufferedFunction


class CondensedQp:
    """The QP above for ``n_u`` inputs, ``n_x_rows`` state-bound rows and ``n_rows`` obstacle
    rows; ``rho`` and ``eps`` are the slack's linear and quadratic weights."""

    def __init__(self, n_u: int, n_x_rows: int, n_rows: int, rho: float, eps: float) -> None:
        self._n_u, self._n_x_rows = n_u, n_x_rows
        n_a = n_x_rows + n_rows
        qp = ca.conic(
            f"gn_sqp_qp_{n_rows}",
            "daqp",
            {"h": ca.Sparsity.dense(n_u + 1, n_u + 1), "a": ca.Sparsity.dense(n_a, n_u + 1)},
            {"error_on_fail": False},
        )
        self._qp = BufferedFunction(qp)
        arg = {name: self._qp.inputs[qp.index_in(name)] for name in qp.name_in()}
        self._h, self._a = arg["h"], arg["a"]
        self._g, self._lba, self._uba, self._lbz, self._ubz = (
            arg[name].reshape(-1, order="F") for name in ("g", "lba", "uba", "lbx", "ubx")
        )
        self._h[n_u, n_u] = eps
        self._g[n_u] = rho
        self._a[:n_x_rows, n_u] = 0.0
        self._a[n_x_rows:, n_u] = 1.0
        self._uba[n_x_rows:] = np.inf
        self._lbz[n_u] = 0.0
        self._ubz[n_u] = np.inf
        self._x = self._qp.outputs[qp.index_out("x")].reshape(-1, order="F")
        self._az = np.zeros(n_a)  # A z, then the rows' violations
        self._zv = np.zeros(n_u + 1)  # the bounds' violations
        self._nan = np.full(n_u, np.nan)

    def solve(
        self,
        hess: np.ndarray,
        grad: np.ndarray,
        a_x: np.ndarray,
        lba_x: np.ndarray,
        uba_x: np.ndarray,
        a_h: np.ndarray,
        lba_h: np.ndarray,
        lbx: np.ndarray,
        ubx: np.ndarray,
    ) -> tuple[np.ndarray, float]:
        """(du (n_u,), the solution's largest violation of its own constraints): H (n_u, n_u),
        g (n_u,), A_x (n_x_rows, n_u), lba_x, uba_x (n_x_rows,), A_h (n_rows, n_u), lba_h
        (n_rows,), lbx, ubx (n_u,). A failed solve shows up as a large or NaN violation (NaN
        du too when DAQP could not start: bounds NaN or crossed, a Hessian it cannot factor)."""
        n_u, n_x_rows = self._n_u, self._n_x_rows
        self._h[:n_u, :n_u] = hess
        self._g[:n_u] = grad
        self._a[:n_x_rows, :n_u] = a_x
        self._a[n_x_rows:, :n_u] = a_h
        self._lba[:n_x_rows] = lba_x
        self._lba[n_x_rows:] = lba_h
        self._uba[:n_x_rows] = uba_x
        self._lbz[:n_u] = lbx
        self._ubz[:n_u] = ubx
        # DAQP leaves x unwritten when it cannot factor H (not positive definite): NaN then,
        # not the previous call's answer
        z = self._x
        z.fill(np.nan)
        try:
            self._qp.evaluate()
        except RuntimeError:  # CasADi refuses ill-posed bounds (NaN, lower > upper, lower inf)
            return self._nan.copy(), float("nan")
        # the largest of lba - A z, A z - uba, lbz - z, z - ubz and 0; NaN propagates
        az, zv = self._az, self._zv
        np.matmul(self._a, z, out=az)
        np.subtract(self._lbz, z, out=zv)
        np.maximum(zv, z - self._ubz, out=zv)
        violation = zv.max()
        if az.size:
            np.maximum(self._lba - az, np.subtract(az, self._uba, out=az), out=az)
            violation = np.maximum(violation, az.max())
        return z[:n_u].copy(), float(np.maximum(violation, 0.0))
