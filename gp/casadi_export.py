"""Export a GP posterior as a CasADi Function for the NMPC.

The Function has one input ``z`` (the feature vector, (d,), in the order of the model's feature
definition) and two outputs ``mean`` and ``var`` ((n_out,) each, the latent mean and variance of
the residual, e.g. m/s^2 and (m/s^2)^2). Everything that does not depend on z (alpha, R) is a
constant, so the graph is k(z, Z) @ alpha per output (plus |R k|^2 for the variance): about
m (d + 2) operations for the mean and m^2 more for the variance. It is an MX graph of dense
matrix operations (faster than the scalar SX expansion of the m x m quadratic form); call
``.expand()`` on it to obtain an SX Function for an SX-based solver.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gp.posterior import Posterior


def posterior_function(
    posterior: Posterior, *, name: str = "gp_residual", include_variance: bool = True
) -> ca.Function:
    """CasADi Function z (d,) -> mean (n_out,) [, var (n_out,)] equal to ``posterior.predict``.

    Args:
        posterior: the fitted model's cached posterior.
        name: Function name.
        include_variance: add the ``var`` output (latent variance, clipped at 0).
    """
    d = posterior.n_features
    z = ca.MX.sym("z", d)
    means, variances = [], []
    for j in range(posterior.n_outputs):
        support = posterior.support[j]
        m = support.shape[0]
        scaled = (ca.repmat(z.T, m, 1) - ca.DM(support)) / ca.repmat(
            ca.DM(posterior.lengthscales[j]).T, m, 1
        )
        k = posterior.variance[j] * ca.exp(-0.5 * ca.sum2(scaled * scaled))
        means.append(posterior.y_offset[j] + ca.dot(ca.DM(posterior.alpha[j]), k))
        if include_variance:
            quad = ca.sumsqr(ca.mtimes(ca.DM(posterior.var_factor[j]), k))
            variances.append(ca.fmax(posterior.variance[j] - quad, 0.0))
    outputs = [ca.vertcat(*means)]
    names = ["mean"]
    if include_variance:
        outputs.append(ca.vertcat(*variances))
        names.append("var")
    return ca.Function(name, [z], outputs, ["z"], names)


class BufferedCall:
    """Low-overhead repeated evaluation of a CasADi Function from Python.

    ``Function.__call__`` converts arguments and results on every call (about 15-20 us);
    this binds NumPy buffers once (CasADi's ``Function.buffer``) so a call costs little more
    than the evaluation itself. Single dense vector inputs and outputs only.
    """

    def __init__(self, function: ca.Function) -> None:
        self.function = function
        self._buffer, self._eval = function.buffer()
        self._inputs = [np.zeros(function.nnz_in(i)) for i in range(function.n_in())]
        self._outputs = [np.zeros(function.nnz_out(i)) for i in range(function.n_out())]
        for i, arr in enumerate(self._inputs):
            self._buffer.set_arg(i, memoryview(arr))
        for i, arr in enumerate(self._outputs):
            self._buffer.set_res(i, memoryview(arr))

    def __call__(self, *inputs: np.ndarray) -> tuple[np.ndarray, ...]:
        """Evaluate; returns views into internal buffers (copy them to keep results)."""
        for dst, src in zip(self._inputs, inputs, strict=True):
            dst[:] = src
        self._eval()
        return tuple(self._outputs)
