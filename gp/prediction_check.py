"""Never worse than not learning: a learned model's multi-step prediction on held-out logs.

Before a learned model flies it must predict the vehicle better than the model it would
replace, over the horizon the NMPC plans on (N x dt, 2 s for [Kulathunga23]'s 20 x 0.1 s).
From every ``stride``-th row k of a clean segment of a held-out log, each model is rolled out
open loop under the *logged* commands u(k..k+H-1), starting from the measured state at k
(one RK4 step per log row, of that row's dt, residual g(z) evaluated at every stage as in the
NMPC; an autopilot integrator state starts as the companion plans from it: as rebuilt from the
log with a residual, 0 without one, companion.nmpc_planner; a previous velocity
(planners.velocity_history) is, at every step, the velocity its lag earlier: measured before
k, predicted after), and the predicted position is compared with the measured one:

    e = sqrt(mean over starts k and steps h = 1..H of |p_hat(k+h) - p(k+h)|^2)     [m]

with H = round(horizon_s / dt). Position, because position tracking is what the NMPC is asked
for, and it integrates every velocity error over the horizon ([Ostafew16] judges its learned
model the same way: by the path-tracking error it leads to). The candidate passes when its error
is below the incumbent's (strictly); a refusal is one line naming both errors.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from flightlog.schema import FlightLog
from gp.datasets import DatasetConfig, split_segments
from gp.errors import DatasetError
from gp.features import feature_definition
from gp.log_signals import model_input, model_state
from gp.model_io import ResidualModel
from planners.nominal_models import (
    HISTORY_STATES,
    INTEGRATOR_STATES,
    VELOCITY_STATES,
    NominalModel,
)
from planners.residual import ResidualTerm

_POS = ("pos_n_m", "pos_e_m", "pos_d_m")
# Rollouts step with each row's own dt, so a late telemetry row (a MAVLink log on a busy
# computer) need not end the segment; only a real gap (mode change, dropout) does.
CHECK_MAX_GAP_FACTOR = 5.0


@dataclass(frozen=True, eq=False)
class Predictor:
    """A model as it would fly: a nominal model and, optionally, a learned residual on it."""

    name: str
    model: NominalModel
    residual: ResidualModel | None = None

    @classmethod
    def of_residual_model(cls, residual: ResidualModel, name: str = "learned") -> Predictor:
        """The residual model on the nominal model it was trained against, as the NMPC plans
        with it (FeatureDefinition.planner_model)."""
        return cls(name, residual.features.planner_model(), residual)

    @classmethod
    def as_flown(cls, residual: ResidualModel, name: str = "previous") -> Predictor:
        """The model file as the companion flies it: its structure alone when its GP was
        refused (:func:`structure_only`), else the residual on its structure."""
        if structure_only(residual):
            return cls(name, residual.features.nominal())
        return cls.of_residual_model(residual, name)

    @property
    def history_lag(self) -> int:
        """Log rows back to the previous velocity the model carries, 0 without one."""
        return self.residual.features.history_lag if self.residual is not None else 0

    def start_states(self, x: np.ndarray) -> np.ndarray:
        """The states (nx, n) rollouts start from, given the states rebuilt from a log (nx, n):
        without a residual, an integrator state is 0 (offset-free, as the companion plans)."""
        if self.residual is not None:
            return x
        rows = [i for i, c in enumerate(self.model.state_names) if c in INTEGRATOR_STATES]
        x = np.array(x, dtype=float)
        x[rows] = 0.0
        return x

    def step_function(self) -> ca.Function:
        """(x, u, dt [s]) -> x_next, one RK4 step with the residual's mean, if any."""
        x = ca.SX.sym("x", self.model.nx)
        u = ca.SX.sym("u", self.model.nu)
        dt = ca.SX.sym("dt")
        term = None
        if self.residual is not None:
            mean = self.residual.flight_mean_function()
            term = ResidualTerm(mean, self.residual.features.planner_map(self.model))
        return ca.Function("step", [x, u, dt], [self.model.rk4_step(x, u, dt, term)])


@dataclass(frozen=True)
class PredictionCheck:
    """The verdict: both models' horizon position-prediction RMSE on the held-out logs.

    Attributes:
        candidate, incumbent: the models' names.
        candidate_rmse_m, incumbent_rmse_m: prediction RMSE over the horizon [m].
        horizon_s: prediction horizon [s]; n_starts: rollouts per model.
    """

    candidate: str
    incumbent: str
    candidate_rmse_m: float
    incumbent_rmse_m: float
    horizon_s: float
    n_starts: int

    @property
    def passed(self) -> bool:
        return self.candidate_rmse_m < self.incumbent_rmse_m

    @property
    def gain(self) -> float:
        """incumbent / candidate RMSE (> 1: the candidate predicts better)."""
        return self.incumbent_rmse_m / max(self.candidate_rmse_m, 1e-12)

    def describe(self) -> str:
        """One line: the verdict and both errors."""
        verdict = "beats" if self.passed else "does NOT beat"
        return (
            f"{self.candidate} {verdict} {self.incumbent} over a {self.horizon_s:g} s horizon on "
            f"held-out logs: position prediction RMSE {self.candidate_rmse_m:.4f} m vs "
            f"{self.incumbent_rmse_m:.4f} m ({self.n_starts} rollouts)"
        )

    def to_dict(self) -> dict[str, object]:
        return {
            "candidate": self.candidate,
            "incumbent": self.incumbent,
            "candidate_rmse_m": self.candidate_rmse_m,
            "incumbent_rmse_m": self.incumbent_rmse_m,
            "horizon_s": self.horizon_s,
            "n_starts": self.n_starts,
            "passed": self.passed,
        }


def horizon_prediction_rmse(
    predictor: Predictor,
    logs: Sequence[FlightLog],
    horizon_s: float,
    modes: tuple[str, ...] | None = None,
    stride: int = 5,
) -> tuple[float, int]:
    """(RMSE [m] of the predicted position over the horizon, number of rollouts).

    Raises:
        DatasetError: no clean segment is longer than the horizon.
    """
    config = DatasetConfig(
        feature_definition("velocity"), max_gap_factor=CHECK_MAX_GAP_FACTOR, modes=modes
    )
    sq_sum, count, starts = 0.0, 0, 0
    for log in logs:
        for seg in split_segments(log, config):
            t = seg["t_s"]
            dt = float(np.median(np.diff(t)))
            steps = int(round(horizon_s / dt))
            k0 = np.arange(0, seg.n_rows - steps, stride)
            if steps < 1 or k0.size == 0:
                continue
            lag = predictor.history_lag
            x = predictor.start_states(model_state(predictor.model, seg, lag)[k0].T)
            u_all = model_input(predictor.model, seg)
            pos = seg.stack(*_POS)
            step = predictor.step_function().map(k0.size)
            p_index = [predictor.model.state_names.index(c) for c in _POS]
            history = _History(predictor.model, seg, k0, lag) if lag else None
            for h in range(steps):
                if history is not None:
                    x = history.fill(np.asarray(x), h)
                x = step(x, u_all[k0 + h].T, (t[k0 + h + 1] - t[k0 + h])[None, :])
                if history is not None:
                    history.append(np.asarray(x))
                err = np.asarray(x)[p_index].T - pos[k0 + h + 1]
                sq_sum += float(np.sum(err**2))
                count += k0.size
            starts += k0.size
    if count == 0:
        raise DatasetError(
            f"no clean segment of the held-out logs is longer than the {horizon_s:g} s horizon; "
            "hold out longer flights"
        )
    return float(np.sqrt(sq_sum / count)), starts


class _History:
    """The previous velocity of rollouts from rows ``k0`` (n,) of a segment: at step h (row
    k0 + h), the velocity ``lag`` rows earlier, measured (the segment's first before it) until
    the rollout has predicted it."""

    def __init__(self, model: NominalModel, seg: FlightLog, k0: np.ndarray, lag: int) -> None:
        self._rows = [model.state_names.index(c) for c in HISTORY_STATES]
        self._vel_rows = [model.state_names.index(c) for c in VELOCITY_STATES]
        self._measured = seg.stack(*VELOCITY_STATES)
        self._k0, self._lag = k0, lag
        self._predicted: list[np.ndarray] = []  # velocity (3, n) after step 0, 1, ...

    def fill(self, x: np.ndarray, h: int) -> np.ndarray:
        """States x (nx, n) before step h with their previous velocity set."""
        back = h - self._lag  # the step whose start holds the previous velocity
        if back >= 1:
            previous = self._predicted[back - 1]
        else:
            previous = self._measured[np.maximum(self._k0 + back, 0)].T
        x = np.array(x, dtype=float)
        x[self._rows] = previous
        return x

    def append(self, x: np.ndarray) -> None:
        """Record the velocity of the states x (nx, n) after the next step."""
        self._predicted.append(x[self._vel_rows])


def check_prediction(
    candidate: Predictor,
    incumbent: Predictor,
    logs: Sequence[FlightLog],
    horizon_s: float,
    modes: tuple[str, ...] | None = None,
) -> PredictionCheck:
    """Compare ``candidate`` with the ``incumbent`` it would replace on held-out ``logs``."""
    cand, n = horizon_prediction_rmse(candidate, logs, horizon_s, modes)
    inc, _ = horizon_prediction_rmse(incumbent, logs, horizon_s, modes)
    return PredictionCheck(candidate.name, incumbent.name, cand, inc, horizon_s, n)


def split_logs(
    logs: Sequence[FlightLog],
    fraction: float = 0.25,
    modes: tuple[str, ...] | None = None,
    rotate: bool = False,
) -> tuple[list[FlightLog], list[FlightLog]]:
    """(training, held-out) logs: every round(1/fraction)-th log is held out when there are at
    least 1/fraction + 1 of them; otherwise each log is cut in time, a ``fraction`` of its rows
    in ``modes`` (all rows if None) held out (a single flight still gets a check it was not
    trained on): the last of them, or with ``rotate`` the i-th log's i-th part counted back
    from its end (log 0: the last, log 1: the one before, ...).

    Why ``rotate``: logs of one repeated path all cut at their last part hold out the same
    stretch of the path, which no model trained on the rest ever sees, so the check judges
    every fit on an extrapolation; rotated, each held-out part is a stretch the other logs
    train on (up to 1/fraction logs)."""
    every = max(2, int(round(1.0 / fraction)))
    if len(logs) > every:
        held = [log for i, log in enumerate(logs) if i % every == every - 1]
        train = [log for i, log in enumerate(logs) if i % every != every - 1]
        return train, held
    train, held = [], []
    for i, log in enumerate(logs):
        rows = np.arange(log.n_rows)
        if modes is not None and log.has("mode"):
            rows = np.flatnonzero(np.isin(log["mode"], modes))
        if rows.size == 0:
            train.append(log)
            continue
        first, last = int(rows[0]), int(rows[-1]) + 1
        back = i % every if rotate else 0  # parts counted back from the end
        start = first + int(round((1.0 - (back + 1) * fraction) * (last - first)))
        stop = first + int(round((1.0 - back * fraction) * (last - first))) if back else log.n_rows
        if start > first:  # a part before the held-out one
            train.append(log.slice(0, start))
        if stop < log.n_rows:
            train.append(log.slice(stop, log.n_rows))
        held.append(log.slice(start, stop))
    return train, held


def structure_only(model: ResidualModel) -> bool:
    """True when the model file records that its GP predicts worse over the horizon than its
    own nominal model alone (the identified structure), or that a closed-loop check chose the
    structure alone (the study's experiments.study.closed_loop): then the planner flies that
    structure without the GP, never worse than what was learned without it."""
    check = model.training.get("prediction_check_structure")
    closed_loop = model.training.get("closed_loop_check")
    return (isinstance(check, dict) and check.get("passed") is False) or (
        isinstance(closed_loop, dict) and closed_loop.get("structure_flies") is True
    )


def refusal(model: ResidualModel) -> str | None:
    """One line refusing ``model`` if its file records a failed prediction check, or a check
    without its verdict (a damaged or hand-edited file), else None (also for a model fitted
    without the check)."""
    check = model.training.get("prediction_check")
    if not isinstance(check, dict) or check.get("passed") is True:
        return None
    if "passed" not in check or any(
        key not in check
        for key in ("incumbent", "horizon_s", "candidate_rmse_m", "incumbent_rmse_m")
    ):
        return (
            "refusing the learned model: its file records a prediction check without its "
            "verdict (damaged or edited); fit it again with fit-gp"
        )
    return (
        f"refusing the learned model: it predicts worse than {check['incumbent']} over "
        f"{check['horizon_s']:g} s on held-out logs ({check['candidate_rmse_m']:.4f} m vs "
        f"{check['incumbent_rmse_m']:.4f} m); fly without it or learn from more flights"
    )
