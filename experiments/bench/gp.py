"""GP benchmark (`bench --only gp`): sparse GP fit and CasADi prediction vs scikit-learn.

Data: 3-D velocities v [m/s] (N(0, 1) north/east, N(0, 0.4^2) down), residual per axis
-0.3 v - 0.08 v|v| [m/s^2] plus N(0, 0.05^2) noise, 3 outputs. Figures:
    gp_fit_s          SparseGP fit on n = 20,000 rows, m = 30 (low_speed, 3 restarts) [s]
    gp_fit_rmse       its RMSE against the noise-free residual on 5,000 test rows [m/s^2]
    gp_sklearn_fit_s  scikit-learn exact GP (SE-ARD + white noise, 2 restarts) on the first
                      2,000 rows [s]
Both fits run with one BLAS/OpenMP thread: SparseGP always does (its m-sized algebra gains
nothing from threads), and on cores shared with other work spinning threads slowed the
scikit-learn fit from ~1 min to ~15 min, which made the figure meaningless.
    gp_sklearn_rmse   its RMSE on the same test rows [m/s^2]
    gp_predict_us     one prediction (mean and variance of 3 outputs) through the exported
                      CasADi Function, called with bound buffers (Function.buffer) [us]
    gp_predict_call_us       the same through a plain Function call from Python (argument
                             conversion included) [us]
    gp_predict_ingraph_us    per-point cost inside a CasADi graph (Function.map over 1,000
                             points), what the NMPC pays per GP query [us]
    gp_fit_peak_mib          peak memory the SparseGP fit allocates on the n = 20,000 rows [MiB]
    gp_fit_peak_mib_at_sklearn_n, gp_sklearn_fit_peak_mib
                             the same for SparseGP and scikit-learn on scikit-learn's 2,000
                             rows (one restart each: a restart frees its arrays before the
                             next), the like-for-like pair [MiB]
Memory is the peak of the Python allocator's traced blocks (tracemalloc: NumPy's arrays and
Python objects, not BLAS/LAPACK's internal workspace), measured in fits of their own, apart
from the timed ones (tracing slows allocation).
``quick=True`` shrinks everything (n = 1,500, sklearn n = 100) for a smoke test.
"""

from __future__ import annotations

import time
import tracemalloc
from collections.abc import Callable

import numpy as np
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel
from threadpoolctl import threadpool_limits

from gp.casadi_export import BufferedCall, posterior_function
from gp.inducing import InducingConfig
from gp.sparse_gp import SparseGP

_NOISE_STD = 0.05


def residual_truth(vel_mps: np.ndarray) -> np.ndarray:
    """-0.3 v - 0.08 v|v| per axis [m/s^2] for velocities (n, 3) [m/s]."""
    return -0.3 * vel_mps - 0.08 * vel_mps * np.abs(vel_mps)


def make_data(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Velocities (n, 3) and noisy residuals (n, 3)."""
    vel = rng.normal(size=(n, 3)) * np.array([1.0, 1.0, 0.4])
    return vel, residual_truth(vel) + _NOISE_STD * rng.normal(size=(n, 3))


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """Run the GP benchmark; returns the figures named in the module docstring."""
    n, n_sklearn, n_test, n_calls = (1500, 100, 500, 2000) if quick else (20000, 2000, 5000, 20000)
    rng = np.random.default_rng(0)
    X, Y = make_data(n, rng)
    X_test, _ = make_data(n_test, rng)
    truth = residual_truth(X_test)

    progress(f"gp: SparseGP fit, n={n}, m=30")
    model = _sparse_gp()
    t0 = time.perf_counter()
    model.fit(X, Y)
    fit_s = time.perf_counter() - t0
    mean, _ = model.predict(X_test)
    fit_rmse = float(np.sqrt(np.mean((mean - truth) ** 2)))

    progress(f"gp: scikit-learn exact GP fit, n={n_sklearn}, 2 restarts")
    kernel = ConstantKernel(1.0) * RBF(np.ones(3)) + WhiteKernel(0.1)
    sk = GaussianProcessRegressor(kernel, n_restarts_optimizer=2, normalize_y=True, random_state=0)
    t0 = time.perf_counter()
    with threadpool_limits(limits=1):  # same footing as SparseGP, which fits single-threaded
        sk.fit(X[:n_sklearn], Y[:n_sklearn])
    sk_fit_s = time.perf_counter() - t0
    sk_rmse = float(np.sqrt(np.mean((sk.predict(X_test) - truth) ** 2)))

    progress("gp: peak memory of the fits")
    peak_mib = _fit_peak_mib(lambda: _sparse_gp().fit(X, Y))
    peak_small_mib = _fit_peak_mib(lambda: _sparse_gp().fit(X[:n_sklearn], Y[:n_sklearn]))
    sk_one = GaussianProcessRegressor(kernel, n_restarts_optimizer=0, normalize_y=True)
    sk_peak_mib = _fit_peak_mib(lambda: sk_one.fit(X[:n_sklearn], Y[:n_sklearn]))

    progress("gp: CasADi prediction")
    function = posterior_function(model.posterior_)
    buffered = BufferedCall(function)
    x0 = X_test[0].copy()
    predict_us = _per_call_us(lambda: buffered(x0), n_calls)
    call_us = _per_call_us(lambda: function(x0), max(n_calls // 10, 200))
    mapped = function.map(1000)
    batch = X_test[:1000].T.copy() if n_test >= 1000 else np.resize(X_test.T, (3, 1000))
    ingraph_us = _per_call_us(lambda: mapped(batch), 20) / 1000.0
    return {
        "gp_fit_s": fit_s,
        "gp_fit_rmse": fit_rmse,
        "gp_sklearn_fit_s": sk_fit_s,
        "gp_sklearn_rmse": sk_rmse,
        "gp_predict_us": predict_us,
        "gp_predict_call_us": call_us,
        "gp_predict_ingraph_us": ingraph_us,
        "gp_fit_peak_mib": peak_mib,
        "gp_fit_peak_mib_at_sklearn_n": peak_small_mib,
        "gp_sklearn_fit_peak_mib": sk_peak_mib,
    }


def _sparse_gp() -> SparseGP:
    """The benchmark's SparseGP: low_speed inducing points, m = 30, seeded."""
    return SparseGP(inducing=InducingConfig(strategy="low_speed", m=30), random_state=0)


def _fit_peak_mib(fit: Callable[[], object]) -> float:
    """Peak traced memory [MiB] while ``fit()`` runs, one BLAS thread (as the timed fits)."""
    with threadpool_limits(limits=1):
        tracemalloc.start()
        try:
            fit()
            return tracemalloc.get_traced_memory()[1] / 2**20
        finally:
            tracemalloc.stop()


def _per_call_us(call: Callable[[], object], n: int) -> float:
    """Median over 5 rounds of the mean wall time of ``n // 5`` calls [us]."""
    call()
    rounds = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(max(n // 5, 1)):
            call()
        rounds.append((time.perf_counter() - t0) / max(n // 5, 1) * 1e6)
    return float(np.median(rounds))
