"""Titsias' collapsed variational bound for sparse GP regression (SGPR), with analytic gradients.

For one output y (n,), inputs X (n, d), inducing points Z (m, d), SE-ARD kernel k and noise
variance s2, with Kuu = k(Z, Z) + jitter, Kuf = k(Z, X), Qff = Kuf^T Kuu^-1 Kuf:

    F = log N(y | 0, Qff + s2 I) - tr(Kff - Qff) / (2 s2)   <=   log p(y)

Everything is computed in the whitened form A = L^-1 Kuf / s (L = chol(Kuu)), B = I + A A^T,
at O(n m^2) cost and O(n m) memory. The gradients follow from dF/dKuu, dF/dKuf and dF/ds2
(written with Sigma = Kuu + Kuf Kfu / s2 = L B L^T) and the kernel's chain rule.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import linalg

from gp.hyperopt import ObjectiveValue
from gp.kernels import (
    SquaredExponentialARD,
    se_ard_gradient_sums,
    se_ard_gradients,
    se_ard_gradients_from_sums,
)
from gp.linalg import jittered_cholesky, solve_lower, solve_upper_t

_LOG_2PI = float(np.log(2.0 * np.pi))


def sgpr_bound(
    X: np.ndarray,
    y: np.ndarray,
    Z: np.ndarray,
    kernel: SquaredExponentialARD,
    noise_variance: float,
    jitter: float = 1e-6,
) -> ObjectiveValue:
    """Collapsed bound F and its gradients wrt log hyperparameters and inducing points.

    The data are visited in blocks of ``BLOCK_ROWS`` rows (twice: sums, then gradients), so the
    (m, block) kernel matrices stay in cache.

    Args:
        X: (n, d) inputs; y: (n,) targets (zero prior mean); Z: (m, d) inducing points.
        kernel: SE-ARD kernel; noise_variance: s2 > 0 in output units squared.
        jitter: added to Kuu's diagonal, relative to the kernel variance.

    Returns:
        ObjectiveValue with the bound (nats) and its gradients (grad_support is dF/dZ (m, d)).
    """
    n, m = y.shape[0], Z.shape[0]
    s2 = float(noise_variance)
    sf2 = kernel.variance
    st = _Statistics.of(X, y, Z, kernel, s2, jitter)
    yy = float(y @ y)
    tr_aat = float(np.trace(st.AAT))
    value = (
        -0.5 * n * _LOG_2PI
        - np.log(np.diag(st.LB)).sum()
        - 0.5 * n * np.log(s2)
        - 0.5 * yy / s2
        + 0.5 * float(st.c @ st.c)
        - 0.5 * n * sf2 / s2
        + 0.5 * tr_aat
    )

    eye = np.eye(m)
    Li = st.Li
    Kuu_inv = Li.T @ Li
    Sigma_inv = Li.T @ linalg.cho_solve((st.LB, True), eye, check_finite=False) @ Li
    w = Sigma_inv @ st.b
    Ki_P_Ki = s2 * (Li.T @ st.AAT @ Li)
    G_sigma = -0.5 * Sigma_inv - 0.5 * np.outer(w, w) / s2**2
    G_kuu = 0.5 * Kuu_inv - 0.5 * Ki_P_Ki / s2 + G_sigma
    G_p2 = 2.0 * (G_sigma + 0.5 * Kuu_inv) / s2
    w_y = w / s2**2
    d_s2 = (
        0.5 * float(np.sum(Sigma_inv * st.P)) / s2**2
        - 0.5 * n / s2
        + 0.5 * yy / s2**2
        - float(st.b @ w) / s2**3
        + 0.5 * float(w @ st.P @ w) / s2**4
        + 0.5 * n * sf2 / s2**2
        - 0.5 * tr_aat / s2
    )
    # dF/dKuf = G_p2 @ Kuf + w_y y^T, reduced block by block.
    h_rows = np.zeros(m)
    col_sq = np.zeros(Z.shape[1])
    HB = np.zeros_like(Z)
    for rows, Kb in zip(_blocks(n), st.kuf_blocks, strict=True):
        Hb = (G_p2 @ Kb + np.outer(w_y, y[rows])) * Kb
        hr, cs, hb = se_ard_gradient_sums(Hb, X[rows])
        h_rows += hr
        col_sq += cs
        HB += hb
    gl_uf, gv_uf, gz_uf = se_ard_gradients_from_sums(Z, h_rows, col_sq, HB, kernel.lengthscales)
    gl_uu, gv_uu, gz_uu = se_ard_gradients(G_kuu, st.Kuu, Z, Z, kernel.lengthscales)
    return ObjectiveValue(
        value=float(value),
        grad_log_lengthscales=gl_uf + gl_uu,
        grad_log_variance=gv_uf + gv_uu - 0.5 * n * sf2 / s2,
        grad_log_noise=s2 * d_s2,
        grad_support=gz_uf + 2.0 * gz_uu,
    )


def sgpr_posterior(
    X: np.ndarray,
    y: np.ndarray,
    Z: np.ndarray,
    kernel: SquaredExponentialARD,
    noise_variance: float,
    jitter: float = 1e-6,
) -> tuple[np.ndarray, np.ndarray]:
    """Optimal q(u) of the bound, as prediction weights.

    Returns:
        alpha (m,) and R (m, m) with mean(x) = k(x, Z) @ alpha and
        var(x) = k(x, x) - |R k(Z, x)|^2, where R^T R = Kuu^-1 - Sigma^-1
        = L^-T (I - B^-1) L^-1: with B = V diag(lam) V^T (lam >= 1),
        R = diag(sqrt(1 - 1 / lam)) V^T L^-1.
    """
    st = _Statistics.of(X, y, Z, kernel, float(noise_variance), jitter)
    alpha = solve_upper_t(st.L, solve_upper_t(st.LB, st.c))
    lam, V = np.linalg.eigh(np.eye(Z.shape[0]) + st.AAT)
    shrink = np.sqrt(np.clip(1.0 - 1.0 / lam, 0.0, None))
    return alpha, (shrink[:, None] * V.T) @ st.Li


BLOCK_ROWS = 2048


@dataclass(frozen=True, eq=False)
class _Statistics:
    """Data sums of the bound, accumulated over row blocks in whitened form.

    Kuu (m, m) with jitter, L = chol(Kuu) and Li = L^-1; A = L^-1 Kuf / s; AAT = A A^T (m, m);
    LB = chol(I + AAT); c = LB^-1 A y / s (m,); P = Kuf Kfu (m, m); b = Kuf y (m,);
    kuf_blocks: Kuf for each row block, (m, block).
    """

    Kuu: np.ndarray
    L: np.ndarray
    Li: np.ndarray
    P: np.ndarray
    b: np.ndarray
    AAT: np.ndarray
    LB: np.ndarray
    c: np.ndarray
    kuf_blocks: list[np.ndarray]

    @classmethod
    def of(
        cls,
        X: np.ndarray,
        y: np.ndarray,
        Z: np.ndarray,
        kernel: SquaredExponentialARD,
        s2: float,
        jitter: float,
    ) -> _Statistics:
        m = Z.shape[0]
        K = kernel(Z, Z)
        L, used = jittered_cholesky(K, jitter * kernel.variance)
        blocks = [kernel(Z, X[rows]) for rows in _blocks(X.shape[0])]
        AAT = np.zeros((m, m))
        Ay = np.zeros(m)
        Li = solve_lower(L, np.eye(m))  # one m x m inverse: a GEMM per block beats a TRSM
        for rows, Kb in zip(_blocks(X.shape[0]), blocks, strict=True):
            Ab = Li @ Kb
            AAT += Ab @ Ab.T
            Ay += Ab @ y[rows]
        AAT /= s2
        LB = linalg.cholesky(np.eye(m) + AAT, lower=True, check_finite=False)
        c = solve_lower(LB, Ay) / s2
        P = s2 * (L @ AAT @ L.T)
        b = L @ Ay
        return cls(K + used * np.eye(m), L, Li, P, b, AAT, LB, c, blocks)


def _blocks(n: int) -> list[slice]:
    return [slice(i, min(i + BLOCK_ROWS, n)) for i in range(0, n, BLOCK_ROWS)]
