"""[Ostafew16] section 3.4: feedback vs MPC vs LB-NMPC on z_{k+1} = a z_k + dt b u_k + dt d_k.

True a = 0.99, b = 0.5 (unknown to the controllers), a time-varying disturbance d_k and a
stepped desired state z_d. Feedback: u = k_fb (z_d - z) (eq. 27). MPC: nominal model
z_{k+1} = z_k + dt u_k (eq. 28), horizon K = 10, Q = 10, R = 0.01 (unconstrained, so the
quadratic programme is solved exactly by least squares). LB-NMPC: the same plus a learned
disturbance g(k) (eq. 29), a GP over the time index fitted to the residuals
z_{k+1} - (z_k + dt u_k) observed in the previous trial (the disturbance is a function of time
in this example). Trial 1 of LB-NMPC has no experience; the figure shows trial 2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gp.exact_gp import exact_posterior
from gp.kernels import SquaredExponentialARD

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@dataclass(frozen=True)
class ExampleConfig:
    a: float = 0.99
    b: float = 0.5
    dt_s: float = 0.1
    steps: int = 300
    horizon: int = 10
    q: float = 10.0
    r: float = 0.01
    k_fb: float = 5.0


def desired(n: int) -> np.ndarray:
    z = np.zeros(n)
    z[50:150] = 1.0
    z[150:220] = -0.5
    return z


def disturbance(n: int, dt_s: float) -> np.ndarray:
    t = np.arange(n) * dt_s
    return 0.5 * np.sin(0.4 * t) + 0.3 * (t > 18.0)


def _plant(c: ExampleConfig, z: float, u: float, d: float) -> float:
    return c.a * z + c.dt_s * c.b * u + c.dt_s * d


def _mpc_input(c: ExampleConfig, z: float, zd: np.ndarray, g: np.ndarray) -> float:
    """Unconstrained MPC on z_{k+1} = z_k + dt u_k + g_k: least squares over u (K,)."""
    K = c.horizon
    L = np.tril(np.ones((K, K))) * c.dt_s  # z_{1..K} = z0 + L u + cumsum(g)
    free = z + np.cumsum(g)
    A = np.vstack([np.sqrt(c.q) * L, np.sqrt(c.r) * np.eye(K)])
    rhs = np.concatenate([np.sqrt(c.q) * (zd - free), np.zeros(K)])
    return float(np.linalg.lstsq(A, rhs, rcond=None)[0][0])


def run(controller: str, c: ExampleConfig = ExampleConfig(), trials: int = 2) -> dict:  # noqa: B008
    """Trajectories of the last trial: {"z", "z_d", "u", "d", "g", "resid"} (steps,) each;
    ``g`` is what the controller used (learned from the trial before), ``resid`` what the
    nominal model missed in this trial, z_{k+1} - (z_k + dt u_k): the disturbance and the model
    error (a, b) together, which is what g learns."""
    n, K = c.steps, c.horizon
    zd, d = desired(n + K + 1), disturbance(n, c.dt_s)
    learned = np.zeros(n + K)
    for _ in range(trials if controller == "lbnmpc" else 1):
        z = np.zeros(n + 1)
        u = np.zeros(n)
        for k in range(n):
            if controller == "feedback":
                u[k] = c.k_fb * (zd[k] - z[k])
            else:
                g = learned[k : k + K] if controller == "lbnmpc" else np.zeros(K)
                u[k] = _mpc_input(c, z[k], zd[k + 1 : k + K + 1], g)
            z[k + 1] = _plant(c, z[k], u[k], d[k])
        g_used = learned[:n].copy()
        resid = z[1:] - (z[:-1] + c.dt_s * u)
        kern = SquaredExponentialARD(np.array([3.0]), 0.05)
        t = np.arange(n, dtype=float)[:, None]
        alpha, _ = exact_posterior(t, resid, kern, 1e-4)
        tq = np.arange(n + K, dtype=float)[:, None]
        learned = kern(tq, t) @ alpha
    return {"z": z[:-1], "z_d": zd[:n], "u": u, "d": d, "g": g_used, "resid": resid}


def tracking_rms(result: dict) -> float:
    return float(np.sqrt(np.mean((result["z"] - result["z_d"]) ** 2)))


def figure(c: ExampleConfig = ExampleConfig()) -> tuple[Figure, dict[str, dict]]:  # noqa: B008
    """Fig. 4-like figure and the runs it shows ({controller: :func:`run`'s dict})."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = {name: run(name, c) for name in ("feedback", "mpc", "lbnmpc")}
    t = np.arange(c.steps) * c.dt_s
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax1.plot(t, runs["mpc"]["z_d"], "g", label="desired z_d")
    for name, shown, style in (("feedback", "feedback", "r"), ("mpc", "MPC", "b"),
                               ("lbnmpc", "LB-NMPC", "k")):  # fmt: skip
        rms = tracking_rms(runs[name])
        ax1.plot(t, runs[name]["z"], style, label=f"{shown} (RMS error {rms:.3f})")
    ax1.set_ylabel("state z [-]")
    ax1.legend(loc="upper right", fontsize="small")
    ax2.plot(t, runs["mpc"]["d"], "m", label="disturbance d_k")
    lb = runs["lbnmpc"]
    ax2.plot(t, lb["resid"] / c.dt_s, "c", label="nominal model's miss / dt (d_k + model error)")
    ax2.plot(t, lb["g"] / c.dt_s, "k--", label="learned g / dt (from trial 1)")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("z per second [1/s]")
    ax2.legend(loc="upper right", fontsize="small")
    fig.suptitle("[Ostafew16] section 3.4: feedback vs MPC vs LB-NMPC (LB-NMPC trial 2)")
    fig.tight_layout()
    return fig, runs


def write_figure(path: str, c: ExampleConfig = ExampleConfig()) -> dict[str, float]:  # noqa: B008
    """Fig. 4-like PNG, written whole or not at all; returns the RMS tracking error of each
    controller.

    Raises:
        OutputError: ``path`` cannot be written (one line).
    """

    from flightlog.atomic_output import write_figure_atomic

    fig, runs = figure(c)
    write_figure_atomic(fig, path, dpi=100)
    return {name: tracking_rms(r) for name, r in runs.items()}
