"""Residual datasets from flight logs ([Kulathunga23], eq. 5).

For each control step k of a clean segment, with H = the feature definition's residual_steps
and T_k = t[k+H] - t[k]:

    y_k = (v_measured(t[k+H]) - v_predicted(t[k+H])) / T_k        [m/s^2, NED]

where v_predicted is the nominal model's velocity H steps after the measured state at k under
the logged commands u(k..k+H-1) (one RK4 step per row, of its own dt; for H = 1 and the
default kinematic_4dof model, the commanded velocity itself, [Kulathunga23] eq. 5). H > 1
measures the residual over the planner's interval: the mean acceleration the nominal model
misses over it, which is how the NMPC applies it (constant over each 0.1 s interval). The
input row z_k is the feature definition's columns at k minus their lags (a negative lag -L: the
change x[k] - x[k-L]).

Segments: a log is split where the time step exceeds ``max_gap_factor`` times its median step,
where ``mode`` changes, and where ``armed`` is 0; segments in modes not listed in ``modes``
and segments too short for the lags are dropped. Non-finite values in a used column are an
error naming the log, row and column (a FlightLog read from disk is already finite).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from flightlog.schema import REQUIRED_COLUMNS, FlightLog
from gp.errors import DatasetError
from gp.features import FeatureDefinition
from gp.log_signals import model_input, model_state

_VEL = ("vel_n_mps", "vel_e_mps", "vel_d_mps")


@dataclass(frozen=True)
class DatasetConfig:
    """How logs become a residual dataset.

    Attributes:
        features: the feature definition (inputs, outputs, nominal model).
        max_gap_factor: a step longer than this times the log's median step splits the log.
        modes: keep only rows in these flight modes (logs with a ``mode`` column); None keeps all.
        min_segment_rows: segments with fewer rows are dropped.
    """

    features: FeatureDefinition
    max_gap_factor: float = 1.5
    modes: tuple[str, ...] | None = None
    min_segment_rows: int = 5


@dataclass(frozen=True, eq=False)
class ResidualDataset:
    """Inputs and residual targets, one row per usable control step.

    Attributes:
        features: the feature definition that produced X and Y.
        X: (n, d) inputs, feature units; Y: (n, 3) residuals [m/s^2].
        dt_s: (n,) step over which each residual was measured [s].
        vel_ned_mps: (n, 3) measured velocity at k (for plots).
        segment: (n,) index into ``segment_names`` of each row's segment.
        segment_names: "<log>#<i>" per segment.
    """

    features: FeatureDefinition
    X: np.ndarray
    Y: np.ndarray
    dt_s: np.ndarray
    vel_ned_mps: np.ndarray
    segment: np.ndarray
    segment_names: tuple[str, ...]

    @property
    def n_rows(self) -> int:
        return int(self.X.shape[0])

    def subset(self, rows: np.ndarray) -> ResidualDataset:
        """Rows selected by an index or boolean array."""
        return ResidualDataset(
            self.features,
            self.X[rows],
            self.Y[rows],
            self.dt_s[rows],
            self.vel_ned_mps[rows],
            self.segment[rows],
            self.segment_names,
        )

    def summary(self) -> dict[str, object]:
        """JSON-ready description: sizes, segments, input ranges and residual statistics."""
        return {
            "n_rows": self.n_rows,
            "n_segments": int(np.unique(self.segment).size),
            "segments": list(self.segment_names),
            "median_dt_s": float(np.median(self.dt_s)),
            "input_min": self.X.min(axis=0).tolist(),
            "input_max": self.X.max(axis=0).tolist(),
            "input_mean": self.X.mean(axis=0).tolist(),
            "residual_mean": self.Y.mean(axis=0).tolist(),
            "residual_std": self.Y.std(axis=0).tolist(),
        }


def residual_dataset(logs: Sequence[FlightLog], config: DatasetConfig) -> ResidualDataset:
    """Build the dataset from one or more logs; raises DatasetError if nothing usable is left."""
    parts: list[tuple[np.ndarray, ...]] = []
    names: list[str] = []
    for log in logs:
        _check_finite(log, config.features)
        for i, seg in enumerate(split_segments(log, config)):
            part = _segment_rows(seg, config.features)
            if part is not None:
                parts.append((*part, np.full(part[0].shape[0], len(names))))
                names.append(f"{_name(log)}#{i}")
    if not parts:
        raise DatasetError(f"no usable rows in {len(logs)} log(s): {_why_unusable(logs, config)}")
    X, Y, dt, vel, seg = (np.concatenate(p) for p in zip(*parts, strict=True))
    return ResidualDataset(config.features, X, Y, dt, vel, seg.astype(int), tuple(names))


def split_segments(log: FlightLog, config: DatasetConfig) -> list[FlightLog]:
    """Contiguous clean pieces of a log: no gap, one mode, armed; long enough."""
    n = log.n_rows
    dt = np.diff(log["t_s"])
    if dt.size == 0:
        return []
    cut = dt > config.max_gap_factor * float(np.median(dt))
    keep = np.ones(n, dtype=bool)
    if log.has("mode"):
        mode = log["mode"]
        cut |= mode[1:] != mode[:-1]
        if config.modes is not None:
            keep &= np.isin(mode, config.modes)
    if log.has("armed"):
        keep &= log["armed"] > 0.5
        cut |= (log["armed"][1:] > 0.5) != (log["armed"][:-1] > 0.5)
    edges = [0, *(np.flatnonzero(cut) + 1).tolist(), n]
    features = config.features
    need = max(config.min_segment_rows, features.max_lag + features.residual_steps + 1)
    return [
        log.slice(a, b)
        for a, b in zip(edges[:-1], edges[1:], strict=True)
        if b - a >= need and keep[a]
    ]


def _why_unusable(logs: Sequence[FlightLog], config: DatasetConfig) -> str:
    """Why no segment of ``logs`` is usable: the rows disarmed, in excluded modes, and in
    segments too short, counted over all logs (one clause, with what to fly)."""
    total = disarmed = excluded = 0
    for log in logs:
        total += log.n_rows
        armed = log["armed"] > 0.5 if log.has("armed") else np.ones(log.n_rows, dtype=bool)
        disarmed += int(np.count_nonzero(~armed))
        if log.has("mode") and config.modes is not None:
            excluded += int(np.count_nonzero(armed & ~np.isin(log["mode"], config.modes)))
    if total and disarmed == total:
        return f"all {total} rows are disarmed (the vehicle never flew); use a log of a flight"
    short = total - disarmed - excluded
    parts = [f"{disarmed} disarmed"] if disarmed else []
    if excluded:
        parts.append(f"{excluded} in modes other than {', '.join(config.modes or ())}")
    parts.append(f"{short} in segments shorter than {config.min_segment_rows} rows")
    return f"of {total} rows, {', '.join(parts)}; record longer flights"


def _segment_rows(seg: FlightLog, features: FeatureDefinition) -> tuple[np.ndarray, ...] | None:
    """(X, Y, dt, vel) for one clean segment, or None if it is too short for the lags."""
    n = seg.n_rows
    lag = features.max_lag
    steps = features.residual_steps
    k = np.arange(lag, n - steps)
    if k.size == 0:
        return None
    t = seg["t_s"]
    dt = t[k + steps] - t[k]
    model = features.nominal()
    x = model_state(model, seg)[k]
    u_all = model_input(model, seg)
    if steps == 1:
        v_pred = model.predicted_velocity_np(x, u_all[k], float(np.median(dt)))
    else:  # each row's own step: a wall-clock log's rows are not evenly spaced
        step = _step_with_dt(model).map(k.size)
        xt = x.T
        for i in range(steps):
            xt = step(xt, u_all[k + i].T, (t[k + i + 1] - t[k + i])[None, :])
        v_pred = np.asarray(model.velocity_of.map(k.size)(xt, u_all[k + steps - 1].T)).T
    v_meas = seg.stack(*_VEL)
    Y = (v_meas[k + steps] - v_pred) / dt[:, None]
    X = np.column_stack(
        [seg[c][k - lg] if lg >= 0 else seg[c][k] - seg[c][k + lg] for c, lg in features.inputs]
    )
    return X, Y, dt, v_meas[k]


def _step_with_dt(model) -> ca.Function:
    """(x, u, dt [s]) -> x after one RK4 step of ``model``."""
    x, u, dt = ca.SX.sym("x", model.nx), ca.SX.sym("u", model.nu), ca.SX.sym("dt")
    return ca.Function("step_dt", [x, u, dt], [model.rk4_step(x, u, dt)])


def _check_finite(log: FlightLog, features: FeatureDefinition) -> None:
    for name in dict.fromkeys((*REQUIRED_COLUMNS, *(c for c, _ in features.inputs))):
        values = log[name]
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise DatasetError(
                f"{_name(log)}: row {int(bad[0]) + 1}, column {name} is {values[bad[0]]}; "
                "drop or repair non-finite rows before building a residual dataset"
            )


def _name(log: FlightLog) -> str:
    return str(log.path) if log.path is not None else "<in-memory log>"
