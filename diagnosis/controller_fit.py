"""The velocity controller as a suspect: PX4's velocity-loop gains fitted from the command path.

PX4's velocity controller ([PX4-PositionControl] PositionControl::_velocityControl, mirrored by
``vehicle_sim.flight_control.velocity_control``) commands the acceleration

    a_sp = P e + I integral(e) - D a + a_ff,    e = v_sp - v,

per axis, and turns it into a normalised thrust vector ``thr`` with
``thr_xy = a_sp_xy * hover / g`` while nothing saturates. The logged attitude and thrust give
that thrust vector back (``thr = -R e_z T``), so the horizontal acceleration the controller
commanded is known up to the attitude loop's lag: 1 / MC_ROLL_P from the config, then a short
inner lag (rate loop, motors) chosen from a small grid; the vertical one
(``a_sp_z = (thr_z + hover) g / hover``) up to the motors' lag alone. The horizontal gains
MPC_XY_VEL_P_ACC and MPC_XY_VEL_I_ACC (shared by north and east) and the vertical ones
MPC_Z_VEL_P_ACC and MPC_Z_VEL_I_ACC are then linear least squares per inner lag, corrected
for the velocity noise in the error (:func:`_best_lag_fit`). Where the commanded
acceleration exceeds the tilt or thrust limits PX4's anti-windup changes the integrator, so
those rows are left out and cut the flight into blocks, each with its own constant per axis for
the integrator's unknown state (which also absorbs steady drag and wind); the first
``SETTLE_S`` of each block, where the lag still carries the cut-off part, is not fitted. The
saturated rows are found with the config's gains, then again with the fitted ones.

The D gains (MPC_XY_VEL_D_ACC, and MPC_Z_VEL_D_ACC, which PX4 has with default 0)
are held at the config's values: D acts on the acceleration the thrust itself produces, so
(1 + D) scales P and I alike and the log cannot tell them apart; a D that differs shows up as
P and I off by the same factor. The vertical regression is only a start: its lag model leaves
P and I 5-20 % low even on exact logs; the replay refines P, and I is refitted with that P
(:func:`refit_vertical_integral`).

This regression is our choice (a replay search over five gains costs hundreds of replays); the
diagnosis names ``flight_control`` only if a replay with the fitted gains also beats the config
on held-out windows (:mod:`.command_path`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from diagnosis.forces import GRAVITY_MPS2, acceleration
from diagnosis.noise_floor import white_noise_std
from diagnosis.replay import Window, airborne_runs
from flightlog.schema import FlightLog
from vehicle_sim import SimConfig
from vehicle_sim.params import PX4_PARAMS

XY_GAINS = ("MPC_XY_VEL_P_ACC", "MPC_XY_VEL_I_ACC")
Z_GAINS = ("MPC_Z_VEL_P_ACC", "MPC_Z_VEL_I_ACC")
# Lags after the attitude loop's 1 / MC_ROLL_P (rate loop and motors) tried [s]. Leaving the
# attitude lag free lets the fit trade it against P (seen on hidden gain changes: P 27 % off).
INNER_LAGS_S = (0.0, 0.02, 0.04, 0.07)
SATURATION_MARGIN = 0.8  # rows beyond this fraction of a tilt or thrust limit are left out
SETTLE_S = 0.6
# Bartlett window of the vertical I's standard error [s]: about the longest residual
# correlation the lag model leaves (a second of the vertical loop's response).
HAC_LAG_S = 1.0
MIN_ROWS = 50


class ControllerFitError(ValueError):
    """The logs cannot fit the velocity gains (no thrust, too few unsaturated airborne rows)."""


@dataclass(frozen=True)
class GainFit:
    """Fitted velocity-loop gains.

    Attributes:
        gains: PX4 parameter name -> fitted value, clipped to PX4's bounds.
        at_bound: names whose least-squares value lay outside PX4's bounds.
        lags_s: the lag cascade of the best fit (attitude, inner) [s].
        n_rows: rows used.
    """

    gains: dict[str, float]
    at_bound: tuple[str, ...]
    lags_s: tuple[float, ...]
    n_rows: int


def fit_velocity_gains(
    logs: Sequence[FlightLog], config: SimConfig, train: Sequence[Window]
) -> GainFit:
    """Fit PX4's velocity-loop gains on the rows of the ``train`` windows of ``logs``.

    Raises:
        ControllerFitError: no thrust column, or fewer than ``MIN_ROWS`` usable rows.
    """
    params, hover, runs = _prepare(logs, config, train)
    gains = {name: params[name] for name in (*XY_GAINS, *Z_GAINS)}
    attitude_lag_s = 1.0 / max(params["MC_ROLL_P"], params["MC_PITCH_P"])
    xy_lags = tuple((attitude_lag_s, inner) for inner in INNER_LAGS_S)
    z_lags = tuple((inner,) for inner in INNER_LAGS_S)
    for _ in range(2):
        blocks = [b for run in runs for b in _unsaturated_blocks(run, gains, params, hover)]
        n_rows = int(sum(b["use"].sum() for b in blocks))
        if n_rows < MIN_ROWS:
            raise ControllerFitError(f"only {n_rows} unsaturated airborne training rows")
        xy, lags_s = _best_lag_fit(blocks, (0, 1), xy_lags, params["MPC_XY_VEL_D_ACC"])
        z, z_lag_s = _best_lag_fit(blocks, (2,), z_lags, params["MPC_Z_VEL_D_ACC"])
        raw = dict(zip((*XY_GAINS, *Z_GAINS), (*xy, *z), strict=True))
        gains, at_bound = {}, []
        for name, value in raw.items():
            spec = PX4_PARAMS[name]
            clipped = float(np.clip(value, spec.lo, spec.hi))
            if clipped != value:
                at_bound.append(name)
            gains[name] = clipped
    return GainFit(gains, tuple(at_bound), (*lags_s, *z_lag_s), n_rows)


@dataclass(frozen=True)
class IntegralFit:
    """MPC_Z_VEL_I_ACC fitted with the vertical P held.

    Attributes:
        least_squares: the least-squares value [1/s^2], unclipped.
        std_error: its standard error [1/s^2], robust to the residuals' correlation in time.
        lag_s: the inner lag of the best fit [s].
        n_rows: rows used.
    """

    least_squares: float
    std_error: float
    lag_s: float
    n_rows: int

    @property
    def value(self) -> float:
        """The fit clipped to PX4's bounds [1/s^2]."""
        spec = PX4_PARAMS["MPC_Z_VEL_I_ACC"]
        return float(np.clip(self.least_squares, spec.lo, spec.hi))

    def pinned(self, rel_half_width: float, z: float = 1.96) -> bool:
        """Whether the confidence interval (95 % for the default ``z``) lies within
        ``rel_half_width`` of the clipped value either side."""
        return z * self.std_error <= rel_half_width * self.value

    def interval(self, z: float = 1.96) -> tuple[float, float]:
        """(low, high) confidence interval, 95 % for the default ``z``, clipped to PX4's
        bounds."""
        spec = PX4_PARAMS["MPC_Z_VEL_I_ACC"]
        lo, hi = sorted(
            np.clip(self.least_squares + np.array([-z, z]) * self.std_error, spec.lo, spec.hi)
        )
        return float(lo), float(hi)


def refit_vertical_integral(
    logs: Sequence[FlightLog], config: SimConfig, train: Sequence[Window], gains: dict[str, float]
) -> IntegralFit:
    """MPC_Z_VEL_I_ACC by least squares with the vertical P held at ``gains``' value, with its
    standard error. The replay of an excitation flight hardly sees the vertical I (its vertical
    error sits at the noise floor over 2 s windows; seen: the RMSE 0.0601 m/s at the true I,
    0.0583 at 1.8 times it), and jointly with P the regression's lag model biases it 10-30 %
    low.

    The regressor is the integral of the error as the integrator saw it
    (:func:`_held_integral`: the flown part from the logged position, the commands held for the
    step after them); the integrated noisy velocity biased I 20-60 % low on noisy logs
    (errors in variables) and the commands summed a step early 5-15 % low on exact ones. What is
    left is variance: the thrust telemetry's noise (1-5 %, up to 0.5 m/s^2 in the commanded
    acceleration) against an integral that swings by a few centimetres; the standard error says
    how far the log pins I (:func:`_integral_fit`).

    Raises:
        ControllerFitError: as :func:`fit_velocity_gains`.
    """
    params, hover, runs = _prepare(logs, config, train)
    full = {**{n: params[n] for n in (*XY_GAINS, *Z_GAINS)}, **gains}
    blocks = [b for run in runs for b in _unsaturated_blocks(run, full, params, hover)]
    if int(sum(b["use"].sum() for b in blocks)) < MIN_ROWS:
        raise ControllerFitError("too few unsaturated airborne training rows")
    return _integral_fit(blocks, full["MPC_Z_VEL_P_ACC"], params["MPC_Z_VEL_D_ACC"])


def _prepare(logs, config, train):
    """(PX4 parameters of ``config``, its hover thrust, the airborne runs' regressors)."""
    params = {name: spec.default for name, spec in PX4_PARAMS.items()}
    params.update(dict(config.px4_params))
    hover = config.vehicle.hover_thrust_norm
    max_thrust_n = len(config.vehicle.rotor_spin) * config.vehicle.max_rotor_thrust_n
    runs = [
        run
        for i, log in enumerate(logs)
        for run in _run_regressors(log, [w for w in train if w.log_index == i], hover, max_thrust_n)
    ]
    if not runs:
        raise ControllerFitError("no thrust column or no airborne run with training rows")
    return params, hover, runs


def _run_regressors(
    log: FlightLog, mine: Sequence[Window], hover: float, max_thrust_n: float
) -> list[dict[str, np.ndarray]]:
    """Per airborne run of ``log``: time step, velocity error, acceleration, the commanded
    acceleration recovered from thrust and attitude, the collective thrust, and which rows lie
    in its training windows ``mine``."""
    if log.has("thrust_norm"):
        thrust = log["thrust_norm"]
    elif log.has("thrust_n"):
        thrust = log["thrust_n"] / max_thrust_n
    else:
        return []
    t = log["t_s"]
    vel = log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")
    cmd = log.stack("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps")
    acc = acceleration(log)
    vel_noise = white_noise_std(vel)
    thr = -_body_z_ned(log.stack("q_w", "q_x", "q_y", "q_z")) * thrust[:, None]
    acc_sp = thr * (GRAVITY_MPS2 / hover)
    acc_sp[:, 2] = (thr[:, 2] + hover) * GRAVITY_MPS2 / hover
    in_train = np.zeros(log.n_rows, dtype=bool)
    for w in mine:
        in_train[w.anchor : w.stop] = True
    pos_cols = ("pos_n_m", "pos_e_m", "pos_d_m")
    pos = log.stack(*pos_cols) if log.has(*pos_cols) else np.full_like(vel, np.nan)
    pos_noise = white_noise_std(pos) if np.isfinite(pos).all() else np.zeros(3)
    out = []
    for start, stop in airborne_runs(log):
        rows = slice(start, stop)
        if in_train[rows].any():
            out.append(
                {
                    "dt": np.diff(t[rows], prepend=t[start]),
                    "cmd": cmd[rows],
                    "vel": vel[rows],
                    "pos": pos[rows],
                    "err": cmd[rows] - vel[rows],
                    "acc": acc[rows],
                    "acc_sp": acc_sp[rows],
                    "thrust_norm": thrust[rows],
                    "train": in_train[rows],
                    "vel_noise": vel_noise,
                    "pos_noise": pos_noise,
                }
            )
    return out


def _unsaturated_blocks(run, gains, params, hover):
    """Contiguous stretches of ``run`` in which neither the commanded acceleration (with these
    gains; the integrator's part is not known and left out) nor the measured one comes near
    the tilt or thrust limits; each with its own integral of the error from its start and the
    rows to fit (training rows after ``SETTLE_S``)."""
    err, acc = run["err"], run["acc"]
    a_cmd = np.column_stack(
        [
            gains["MPC_XY_VEL_P_ACC"] * err[:, :2] - params["MPC_XY_VEL_D_ACC"] * acc[:, :2],
            gains["MPC_Z_VEL_P_ACC"] * err[:, 2] - params["MPC_Z_VEL_D_ACC"] * acc[:, 2],
        ]
    )
    xy_limit = SATURATION_MARGIN * GRAVITY_MPS2 * np.tan(np.radians(params["MPC_TILTMAX_AIR"]))
    thr_lo, thr_hi = params["MPC_THR_MIN"], params["MPC_THR_MAX"]
    ok = np.hypot(a_cmd[:, 0], a_cmd[:, 1]) < xy_limit
    ok &= np.hypot(run["acc_sp"][:, 0], run["acc_sp"][:, 1]) < xy_limit
    collective_cmd = hover * (1.0 - a_cmd[:, 2] / GRAVITY_MPS2)
    for collective in (run["thrust_norm"], collective_cmd):
        ok &= (collective > thr_lo / SATURATION_MARGIN) & (collective < SATURATION_MARGIN * thr_hi)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(int), [0]])))
    blocks = []
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        dt = run["dt"][a:b].copy()
        dt[0] = 0.0
        settled = np.cumsum(dt) >= SETTLE_S
        use = run["train"][a:b] & settled
        if use.sum() >= 5:
            e = err[a:b]
            blocks.append(
                {
                    "dt": dt,
                    "err": e,
                    "int": np.cumsum(e * dt[:, None], axis=0),
                    "int_held": _held_integral(
                        run["cmd"][a:b], run["vel"][a:b], run["pos"][a:b], dt
                    ),
                    "acc": acc[a:b],
                    "acc_sp": run["acc_sp"][a:b],
                    "use": use,
                    "vel_noise": run["vel_noise"],
                    "pos_noise": run["pos_noise"],
                }
            )
    return blocks


def _held_integral(cmd: np.ndarray, vel: np.ndarray, pos: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """(n, 3) integral of the velocity error from the first row [m], as the controller's
    integrator sees it: each logged command holds until the next row (it is what was sent and
    stays in force for one step), so it is summed with the step after it, not before; the flown
    part is the position difference when the log has positions (a white position noise stays
    white, where the integrated velocity noise is a random walk that grows with the block:
    0.1 m over a 36 s hover at 0.08 m/s of noise, three times the integrator's own swing), else
    the velocity by the trapezoidal rule. ``dt`` (n,) [s] with dt[0] = 0."""
    commanded = np.vstack([np.zeros((1, 3)), np.cumsum(cmd[:-1] * dt[1:, None], axis=0)])
    if np.isfinite(pos).all():
        flown = pos - pos[0]
    else:
        steps = 0.5 * (vel[1:] + vel[:-1]) * dt[1:, None]
        flown = np.vstack([np.zeros((1, 3)), np.cumsum(steps, axis=0)])
    return commanded - flown


def _body_z_ned(q_wxyz: np.ndarray) -> np.ndarray:
    """(n, 3) body z axis (FRD, pointing down) in NED from (n, 4) unit quaternions."""
    w, x, y, z = q_wxyz.T
    return np.column_stack([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def _lag(u: np.ndarray, dt: float, taus_s: tuple[float, ...]) -> np.ndarray:
    """``u`` (n, k) through a cascade of first-order lags with time constants ``taus_s`` [s],
    discretised exactly for the step ``dt`` [s], starting at rest at u[0]."""
    out = u
    for tau in taus_s:
        if tau <= 0.0:
            continue
        alpha = 1.0 - np.exp(-dt / tau)
        out, _ = lfilter([alpha], [1.0, alpha - 1.0], out, axis=0, zi=(1.0 - alpha) * out[:1])
    return out


def _noise_gain(dt: float, taus_s: tuple[float, ...], n: int = 400) -> float:
    """Variance of white unit noise after the lag cascade ``taus_s`` at step ``dt`` [1]: the
    sum of its squared impulse response (over ``n`` rows)."""
    impulse = np.zeros((n, 1))
    impulse[0] = 1.0
    out = impulse
    for tau in taus_s:
        if tau > 0.0:
            alpha = 1.0 - np.exp(-dt / tau)
            out = lfilter([alpha], [1.0, alpha - 1.0], out, axis=0)
    return float(np.sum(out * out))


def _best_lag_fit(blocks, axes, lags, d_gain):
    """Least-squares [P, I] over ``axes`` for the lag cascade with the smallest residual, with
    the D gain held at ``d_gain``: y = L[P e + I int(e) - D a + c] gives y + D L[a] = P L[e] +
    I L[int(e)] + c. Returns ([P, I], the lag cascade [s]).

    The error e holds the logged velocity's white noise, which the lag passes on with variance
    ``noise_std**2 * _noise_gain`` per row; uncorrected it biases P low (regression dilution:
    20-35 % for the vertical gains at 0.03-0.08 m/s of noise). That expected noise energy is
    taken off the normal equations' P-P term (corrected least squares, [Fuller87] ch. 1.2);
    the noise of int(e) is a random walk of size noise_std * sqrt(dt * t), left alone.

    The constants c (one per block and axis) are taken out by centring each block's rows per
    axis (the Frisch-Waugh-Lovell theorem): the same [P, I] and residual as with a column per
    constant, solved as 2 x 2 normal equations instead of one column per block (hundreds on a
    5-minute log). The noise correction, on the P-P term, is the same on both."""
    best = (np.inf, None, (0.0,))
    for taus in lags:
        blocks_x, blocks_y = [], []
        noise_energy = raw_pp = 0.0
        for block in blocks:
            dt, use = float(np.median(block["dt"][1:])), block["use"]
            filt = {k: _lag(block[k][:, list(axes)], dt, taus) for k in ("err", "int", "acc")}
            gain = _noise_gain(dt, taus)
            for j in range(len(axes)):
                x = np.column_stack([filt["err"][:, j], filt["int"][:, j]])[use]
                y = (block["acc_sp"][:, axes[j]] + d_gain * filt["acc"][:, j])[use]
                raw_pp += float(x[:, 0] @ x[:, 0])
                blocks_x.append(x - x.mean(axis=0))
                blocks_y.append(y - y.mean())
                noise_energy += float(use.sum()) * gain * block["vel_noise"][axes[j]] ** 2
        x_all, y_all = np.vstack(blocks_x), np.concatenate(blocks_y)
        normal = x_all.T @ x_all
        normal[0, 0] -= min(noise_energy, 0.9 * raw_pp)
        coef = np.linalg.lstsq(normal, x_all.T @ y_all, rcond=None)[0]
        sse = float(np.sum((x_all @ coef - y_all) ** 2))
        if sse < best[0]:
            best = (sse, coef[:2], taus)
    return best[1], best[2]


def _integral_fit(blocks, p_gain, d_gain, axis=2, lags=INNER_LAGS_S) -> IntegralFit:
    """Least-squares I on ``axis`` with P held at ``p_gain`` and D at ``d_gain``, for the inner
    lag with the smallest residual: y - P L[e] + D L[a] = I L[int(e)] + c, a constant c per
    block (taken out by centring, as in :func:`_best_lag_fit`), the integral of
    :func:`_held_integral`.

    Its standard error is the heteroskedasticity and autocorrelation consistent one of
    [NeweyWest87] (Bartlett weights over ``HAC_LAG_S``, within blocks): the residuals are
    coloured by the lag filter and by what the lag model misses, and the ordinary standard error
    was about 1.4 times too small on simulated noisy logs.

    A white noise on the logged position stays in the integral (its first row's part is a
    constant the centring takes out); its expected energy after the lag is taken off the
    normal equation as for P in :func:`_best_lag_fit` (corrected least squares, [Fuller87]),
    at most 90 % of it (it is nil on the simulator's exact positions)."""
    best = None
    for tau in lags:
        xs, ys, noise_energy = [], [], 0.0
        for block in blocks:
            dt, use = float(np.median(block["dt"][1:])), block["use"]
            cols = np.column_stack(
                [block["err"][:, axis], block["int_held"][:, axis], block["acc"][:, axis]]
            )
            filt = _lag(cols, dt, (tau,))
            y = block["acc_sp"][:, axis] - p_gain * filt[:, 0] + d_gain * filt[:, 2]
            x, y = filt[use, 1], y[use]
            xs.append(x - x.mean())
            ys.append(y - y.mean())
            noise_energy += (len(x) - 1) * _noise_gain(dt, (tau,)) * block["pos_noise"][axis] ** 2
        raw = float(sum(x @ x for x in xs))
        sxx = raw - min(noise_energy, 0.9 * raw)
        value = float(sum(x @ y for x, y in zip(xs, ys, strict=True))) / max(sxx, 1e-12)
        residuals = [y - value * x for x, y in zip(xs, ys, strict=True)]
        sse = float(sum(r @ r for r in residuals))
        if best is None or sse < best[0]:
            best = (sse, value, tau, xs, residuals, dt, sxx)
    _, value, tau, xs, residuals, dt, sxx = best
    max_lag = max(1, round(HAC_LAG_S / dt))
    meat = 0.0
    for x, r in zip(xs, residuals, strict=True):
        score = x * r
        meat += float(score @ score)
        for k in range(1, min(max_lag, len(score) - 1) + 1):
            meat += 2.0 * (1.0 - k / (max_lag + 1)) * float(score[k:] @ score[:-k])
    n_rows = int(sum(len(x) for x in xs))
    std_error = float(np.sqrt(max(meat, 0.0)) / max(sxx, 1e-12))
    return IntegralFit(float(value), std_error, float(tau), n_rows)
