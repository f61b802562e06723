"""Map flight-log columns onto a nominal model's state and input vectors.

The planners' models name their signals (``pos_n_m``, ``yaw_rad``, ``vel_n_mps``, ...); a log
holds measurements and commands (``vel_n_mps`` measured, ``cmd_vel_n_mps`` commanded, the
attitude as a quaternion). States come from measurements, inputs from the logged commands;
an autopilot velocity integrator (px4_velocity_pi's ``vel_int_*``) is rebuilt from both as the
companion keeps it in flight (gp.velocity_integrator), 0 at the log's (segment's) first row;
a previous velocity (planners.velocity_history's ``vel_prev_*``) is the measured velocity a
given number of rows earlier (the first row's before it).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from flightlog.schema import FlightLog
from gp.errors import DatasetError
from gp.velocity_integrator import velocity_integrator
from planners.nominal_models import (
    HISTORY_STATES,
    INTEGRATOR_STATES,
    VELOCITY_STATES,
    NominalModel,
)


def yaw_from_quaternion(log: FlightLog) -> np.ndarray:
    """Yaw [rad] of the body-to-NED quaternion (w, x, y, z), (n,)."""
    w, x, y, z = (log[c] for c in ("q_w", "q_x", "q_y", "q_z"))
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


_STATE_SIGNALS: dict[str, Callable[[FlightLog], np.ndarray]] = {
    **{c: (lambda log, c=c: log[c]) for c in ("pos_n_m", "pos_e_m", "pos_d_m")},
    **{c: (lambda log, c=c: log[c]) for c in ("vel_n_mps", "vel_e_mps", "vel_d_mps")},
    "yaw_rad": yaw_from_quaternion,
    "heading_rad": yaw_from_quaternion,
}

_INPUT_SIGNALS: dict[str, Callable[[FlightLog], np.ndarray]] = {
    **{f"vel_{a}_mps": (lambda log, a=a: log[f"cmd_vel_{a}_mps"]) for a in "ned"},
    "yaw_rate_radps": lambda log: log["cmd_yaw_rate_radps"],
    "turn_rate_radps": lambda log: log["cmd_yaw_rate_radps"],
    "speed_mps": lambda log: np.hypot(log["cmd_vel_n_mps"], log["cmd_vel_e_mps"]),
}


def model_state(model: NominalModel, log: FlightLog, history_lag: int = 0) -> np.ndarray:
    """The model's state per log row, (n, nx), from measured signals (an integrator state from
    0 at the first row: pass one segment; a previous velocity ``history_lag`` rows back)."""
    table = dict(_STATE_SIGNALS)
    earlier = np.maximum(np.arange(log.n_rows) - history_lag, 0)
    pairs = zip(HISTORY_STATES, VELOCITY_STATES, strict=True)
    table |= {h: (lambda log, c=c: log[c][earlier]) for h, c in pairs}
    if model.integrator_gains:
        integrator = velocity_integrator(log, model.integrator_gains)
        table |= {c: (lambda _log, i=i: integrator[:, i]) for i, c in enumerate(INTEGRATOR_STATES)}
    return _stack(model, log, model.state_names, table, "state")


def model_input(model: NominalModel, log: FlightLog) -> np.ndarray:
    """The model's input per log row, (n, nu), from the logged commands."""
    return _stack(model, log, model.input_names, _INPUT_SIGNALS, "input")


def _stack(
    model: NominalModel,
    log: FlightLog,
    names: tuple[str, ...],
    table: dict[str, Callable[[FlightLog], np.ndarray]],
    kind: str,
) -> np.ndarray:
    unknown = [n for n in names if n not in table]
    if unknown:
        raise DatasetError(
            f"nominal model {model.name!r} has {kind} signals {unknown} that cannot be taken "
            f"from a flight log; known: {', '.join(table)}"
        )
    return np.column_stack([table[n](log) for n in names])
