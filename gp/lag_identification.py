"""Identify the velocity loop's time constants from flight logs (the lag a GP cannot learn).

Paper 000's kinematic model assumes the vehicle flies the commanded velocity. Under an
autopilot's velocity loop it does not: the velocity follows the command with a lag, and that
lag depends on the velocity the vehicle has *now*, a state the kinematic model does not carry,
so a residual model queried inside the kinematic NMPC cannot represent it. Learning therefore
starts with the structure: the time constants of ``first_order_lag`` are fitted to the logs by
least squares on the one-step velocity prediction, and the GP then learns what is left.

For consecutive rows k, k+1 of a clean segment (measured velocity v, logged command u, step
dt), the first-order lag predicts

    v_hat(k+1) = u(k) + (v(k) - u(k)) * exp(-dt / tau)      [m/s]

(the exact discretisation; the RK4 step the NMPC and the residual dataset use agrees to better
than 1e-8 m/s for dt / tau < 0.1). tau minimises the RMSE of v(k+1) - v_hat(k+1) over the
north and east axes; tau_d_s (the vertical loop, tuned separately in PX4) over the down axis,
when the logs excite it, else it is taken equal to tau.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from flightlog.schema import FlightLog
from gp.datasets import DatasetConfig, residual_dataset
from gp.errors import DatasetError
from gp.features import feature_definition

TAU_BOUNDS_S = (0.01, 10.0)
MIN_EXCITATION_MPS = 0.02


@dataclass(frozen=True)
class LagIdentification:
    """Fitted time constants and how much they explain.

    Attributes:
        tau_s: horizontal (north, east) velocity time constant [s].
        tau_d_s: vertical (down) time constant [s] (equal to tau_s if the logs do not excite
            the vertical axis: RMS command-velocity gap below MIN_EXCITATION_MPS).
        vertical_identified: whether tau_d_s was fitted (True) or copied from tau_s.
        kinematic_rmse_mps: (3,) per-axis RMSE of the one-step prediction v_hat = u [m/s].
        lag_rmse_mps: (3,) the same with the identified lag [m/s].
        n_rows: rows used.
    """

    tau_s: float
    tau_d_s: float
    vertical_identified: bool
    kinematic_rmse_mps: tuple[float, float, float]
    lag_rmse_mps: tuple[float, float, float]
    n_rows: int

    def nominal_params(self) -> dict[str, float]:
        """``first_order_lag`` parameters (rounded to 0.1 ms)."""
        return {"tau_s": round(self.tau_s, 4), "tau_d_s": round(self.tau_d_s, 4)}

    def to_dict(self) -> dict[str, object]:
        return {
            "tau_s": self.tau_s,
            "tau_d_s": self.tau_d_s,
            "vertical_identified": self.vertical_identified,
            "kinematic_rmse_mps": list(self.kinematic_rmse_mps),
            "lag_rmse_mps": list(self.lag_rmse_mps),
            "n_rows": self.n_rows,
        }

    def describe(self) -> str:
        """One line: the time constants and the one-step RMSE before and after."""
        before = float(np.linalg.norm(self.kinematic_rmse_mps))
        after = float(np.linalg.norm(self.lag_rmse_mps))
        vertical = "" if self.vertical_identified else " (vertical not excited: copied)"
        return (
            f"velocity lag tau_s={self.tau_s:.3f} s, tau_d_s={self.tau_d_s:.3f} s{vertical}: "
            f"one-step RMSE {before:.4f} m/s (kinematic) -> {after:.4f} m/s on {self.n_rows} rows"
        )


def identify_velocity_lag(
    logs: Sequence[FlightLog], modes: tuple[str, ...] | None = None
) -> LagIdentification:
    """Least-squares time constants of the velocity loop from ``logs`` (rows in ``modes``).

    Raises:
        DatasetError: no usable rows, or no horizontal excitation (the vehicle only hovered).
    """
    features = feature_definition("state_input", "kinematic_4dof", residual_dt_s=1.0)
    data = residual_dataset(logs, DatasetConfig(features, modes=modes))
    vel, cmd = data.X[:, 0:3], data.X[:, 3:6]
    vel_next = cmd + data.Y * data.dt_s[:, None]  # the kinematic prediction is u itself
    gap = vel - cmd
    if np.sqrt(np.mean(gap[:, :2] ** 2)) < MIN_EXCITATION_MPS:
        raise DatasetError(
            f"the logs never command a horizontal velocity change (RMS command gap below "
            f"{MIN_EXCITATION_MPS} m/s): fly a mission that moves before identifying the lag"
        )

    def rmse(tau: float, axes: slice) -> float:
        decay = np.exp(-data.dt_s / tau)[:, None]
        err = vel_next[:, axes] - (cmd[:, axes] + gap[:, axes] * decay)
        return float(np.sqrt(np.mean(err**2)))

    tau = _fit(lambda t: rmse(t, slice(0, 2)))
    vertical = bool(np.sqrt(np.mean(gap[:, 2] ** 2)) >= MIN_EXCITATION_MPS)
    tau_d = _fit(lambda t: rmse(t, slice(2, 3))) if vertical else tau
    taus = np.array([tau, tau, tau_d])
    lag = [rmse(taus[i], slice(i, i + 1)) for i in range(3)]
    kinematic = np.sqrt(np.mean((vel_next - cmd) ** 2, axis=0))
    return LagIdentification(
        tau_s=tau,
        tau_d_s=tau_d,
        vertical_identified=vertical,
        kinematic_rmse_mps=tuple(float(v) for v in kinematic),
        lag_rmse_mps=tuple(lag),
        n_rows=data.n_rows,
    )


def _fit(cost) -> float:
    """argmin over tau in TAU_BOUNDS_S of cost(tau), searched on log(tau)."""
    lo, hi = np.log(TAU_BOUNDS_S)
    result = minimize_scalar(
        lambda s: cost(float(np.exp(s))), bounds=(lo, hi), method="bounded", options={"xatol": 1e-4}
    )
    return float(np.exp(result.x))
