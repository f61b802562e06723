"""Motor lag and thrust curve from the produced thrust's answer to the command, one row ahead.

On a noisy log a motor lag of a few 10 ms hardly shows in the velocity a replay predicts (about
3 mm/s under 30-80 mm/s of velocity noise at 20 Hz), but it shows in the thrust the motors
produce: after a setpoint step the controller's thrust command jumps by newtons within one row,
and the logged rotor thrust (from the motor speeds, after the lag) follows it with the lag. A
thrust curve off by a gain (``thrust_curve``) hides in the replayed velocity the same way (the
velocity loop makes up for it), and shows in the same comparison: the logged thrust swings by
``gain`` times what the controller commanded around hover.

The follower of a replay (:mod:`.replay`) is put into the measured state at every row, so its
flight control sees what the real one saw and commands what the real one commanded (force
effects such as a payload or drag change the state, not this command; the velocity-loop
integral is built from the same measured errors). Its rotor speeds are its own: they follow
those commands through the config's motor lag. Stepping it one row and comparing its total
rotor thrust with the logged one [N] isolates the command path.

The velocity noise of the log enters the follower's command (the real controller saw the
estimator's velocity; a simulated log's noise is added after the flight), and a longer lag or a
thrust-curve gain below 1 shrinks that noise in the follower's thrust (a lag smooths it, a gain
scales it by ``gain``^2), which would bias ``tau_s`` up by 20 % or more at 0.03-0.08 m/s and the
gain down as much (errors in the variables). The fit removes that bias by SIMEX [Cook94]: the
squared thrust error is measured once more with the log's own white velocity noise
(:func:`.noise_floor.white_noise_std`) added again, and extrapolated linearly to no noise,
``2 e^2(noise) - e^2(2 x noise variance)`` (linear it is: measured at 1, 2, 3 and 4 times the
noise variance, the steps agree within 3 %). Every held-out comparison is made on these
extrapolated errors, per row (:class:`HeldOut`), averaged over ``FLOOR_REPLICATES`` draws of the
extra noise as [Cook94] average their replicates. Judged on the raw errors instead, a gain or lag
that merely shrinks the follower's noise "removes" error: on a flight with a hidden thrust curve
of gain 0.83, a motor lag of 31 ms (the preset's is 20 ms) was named first, the lag being the
better smoother, although the thrust curve left far less error.

The logged thrust's noise enters the follower too, through the lead-in, where the velocity
integral is matched to the logged thrust row by row (:mod:`.replay`): the last lead-in row's
noise stays in the integral as an offset of the whole airborne run, scaled by the thrust
curve's gain, and pulled a fitted gain about 5 % low (0.75 for a true 0.82 with 2.2 % thrust
noise). A constant offset over a run is no part of what a lag or a thrust curve makes (the
hover thrust is unchanged by both), so each run's mean error is taken out of the errors
(:meth:`ThrustTracking.sq_error`).

The parameter is fitted on the training windows' rows and judged on the held-out ones like any
cause, in forward selection: each cause of a round is fitted on top of the causes already named;
it passes if it removes at least ``MIN_GAIN_FRACTION`` of the held-out squared thrust error left
above the floor, if the removal is significant by a block bootstrap over the held-out windows (p
<= ``MAX_P_VALUE``), and if it removes at least the least thrust ``MIN_THRUST_FRACTION`` of the
weight in RMS over the rows it acts on (the force causes' least force,
``SelectionConfig.min_force_fraction``); of those that pass, the one that leaves the least
held-out error is named (not the one with the largest fraction: the fractions of two causes
are taken over different floors when the floor depends on the cause), and the others are fitted
again on top of it. A motor lag and a thrust curve are so not exclusive: with both there, the
second is named in the next round. The floor is the logged thrust's own white noise (plus
``FLOOR_MARGIN_SE`` standard errors of that estimate), but never above the least held-out error
a fit of the round reaches (:func:`judge`): with 2-5 % thrust noise the noise is most of the
held-out error, and the one realisation of velocity noise in the log scatters the extrapolated
error by more than the margin (seen: 0.224 N^2 left with the true gain against a noise estimate
of 0.268 N^2), which left nothing "explainable" and named nothing. The guards against naming
noise are then the bootstrap and the least thrust, both on the paired difference, where the
log's noise largely cancels.

The least thrust is a floor on the *removed* mean squared error, not on the explainable part:
with sensor noise independent of the cause, ``mse(before) - mse(after)`` estimates the mean
square of the thrust the cause accounts for whatever the noise (the noise cancels in the
difference), so the rule means the same on exact and on noisy logs. The explainable part has no
such floor on an exact log (the noise floor is zero), where the follower's own small mismatch
(it steps once per row; seen: 0.016 N of one-row-ahead thrust RMSE on a 5-minute log) was half
removed by a 21 ms motor lag that was not there: sqrt(0.016^2 - 0.011^2) = 0.012 N removed,
against 0.044 N of least thrust for a 1.5 kg Iris. A true lag removes far more (seen: 0.522
-> 0.447 N at IMU noise 0.3 m/s^2, 0.27 N removed, for tau_s 0.041 s). What it cannot tell
apart is a lag from the few milliseconds by which a named command delay may be fitted short
(seen on an exact log, before the delay's refinement minimised the squared error
(:mod:`.command_path`): a 24 ms lag removed 0.048 N beside a delay fitted 5 ms short, and was
named; that delay now comes out 0.1 % off).

Needs the produced thrust (``thrust_n`` as logged, or from ESC rotor speeds); PX4's normalised
thrust setpoint is the command itself and shows no lag.

[Cook94] J. R. Cook, L. A. Stefanski: Simulation-extrapolation estimation in parametric
measurement error models. Journal of the American Statistical Association 89 (428), 1994.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from diagnosis import sim_anchor
from diagnosis.cause import Cause
from diagnosis.command_path import grid_order, search_grid, with_cause
from diagnosis.forces import GRAVITY_MPS2
from diagnosis.noise_floor import NOISE_VAR_REL_SE_SQRT_N, block_bootstrap, white_noise_std
from diagnosis.replay import LogArrays, Window, airborne_runs
from diagnosis.selection import SelectionConfig
from diagnosis.warm_up import LEAD_IN_S
from flightlog.schema import FlightLog
from vehicle_sim import SimConfig

MOTOR_LAG = "motor_lag"
THRUST_CURVE = "thrust_curve"
THRUST_RESPONSE_CAUSES = (MOTOR_LAG, THRUST_CURVE)  # command-path causes the thrust response fits
PRODUCED_THRUST_SOURCES = ("thrust_n as logged", "ESC rotor speed")
MIN_GAIN_FRACTION = 0.5
MAX_P_VALUE = 0.01
FLOOR_MARGIN_SE = 2.0  # the floor is an estimate: its standard errors added, as for forces
MIN_THRUST_FRACTION = SelectionConfig().min_force_fraction  # least RMS thrust removed [of weight]
SIMEX_SEED = 0
TRACKED_CHUNK_ROWS = 50  # rows flown in one call after the lead-in (a few seconds of log)
FLOOR_REPLICATES = 4  # draws of the extra velocity noise the held-out SIMEX errors average


@dataclass(frozen=True)
class ThrustTracking:
    """One-row-ahead thrust of the anchored follower against the logged thrust.

    Attributes:
        sim_thrust_n, meas_thrust_n: (m,) simulated and logged total rotor thrust [N].
        window: (m,) index (into the windows given) of the window each row belongs to.
        run: (m,) index of the airborne run (over all logs) each row belongs to.
    """

    sim_thrust_n: np.ndarray
    meas_thrust_n: np.ndarray
    window: np.ndarray
    run: np.ndarray

    def sq_error(self) -> np.ndarray:
        """(m,) squared thrust error per row [N^2], each airborne run's mean error taken out."""
        err = self.sim_thrust_n - self.meas_thrust_n
        if not len(err):
            return err
        runs, inverse = np.unique(self.run, return_inverse=True)
        mean = np.bincount(inverse, err) / np.bincount(inverse)
        return (err - mean[inverse]) ** 2

    def mse(self) -> float:
        """Mean squared thrust error [N^2] (nan without rows)."""
        return float(np.mean(self.sq_error())) if len(self.window) else float("nan")


@dataclass(frozen=True)
class HeldOut:
    """The held-out thrust error of one config at no velocity noise (SIMEX, [Cook94]).

    Attributes:
        tracking: the follower's one-row-ahead thrust on the log as it is.
        sq_error: (m,) per row, ``2 e^2(noise) - mean e^2(2 x noise variance)`` [N^2] over
            ``FLOOR_REPLICATES`` draws of the extra velocity noise: the squared error the row
            would have without the log's velocity noise (unbiased where it grows linearly with
            the noise variance, as it does here).
    """

    tracking: ThrustTracking
    sq_error: np.ndarray

    @classmethod
    def of(
        cls,
        config: SimConfig,
        logs: Sequence[FlightLog],
        test: Sequence[Window],
        vel_noise_mps: np.ndarray,
    ) -> HeldOut:
        """``config``'s held-out thrust error on ``test`` (``vel_noise_mps`` (3,) [m/s])."""
        once = track_thrust(config, logs, test)
        extra = np.asarray(vel_noise_mps, float)
        twice = [track_thrust(config, logs, test, extra, r) for r in range(FLOOR_REPLICATES)]
        noisier = np.mean([t.sq_error() for t in twice], axis=0)
        return cls(once, 2.0 * once.sq_error() - noisier)

    def mse(self) -> float:
        """Mean squared thrust error at no velocity noise [N^2] (nan without rows)."""
        return float(np.mean(self.sq_error)) if len(self.sq_error) else float("nan")


@dataclass(frozen=True)
class ThrustFit:
    """A thrust-response cause fitted on the training windows, with its held-out errors.

    Attributes:
        name, param, value: the cause, its parameter and the fitted value.
        at_bound: the fit is on the edge of the search grid.
        before, after: held-out thrust error without and with the cause.
    """

    name: str
    param: str
    value: float
    at_bound: bool
    before: HeldOut
    after: HeldOut


def produced_thrust(sources: Sequence[str]) -> bool:
    """Whether every log's ``thrust_n`` is the produced (not the commanded) thrust."""
    return bool(sources) and all(s.startswith(PRODUCED_THRUST_SOURCES) for s in sources)


def track_thrust(
    config: SimConfig,
    logs: Sequence[FlightLog],
    wins: Sequence[Window],
    extra_vel_noise_mps: np.ndarray | None = None,
    replicate: int = 0,
) -> ThrustTracking:
    """The follower's thrust one row after each row of ``wins`` (rows [anchor, stop - 1));
    ``extra_vel_noise_mps`` (3,): std of white noise added to the anchored velocity (seeded by
    ``replicate``: the same draw for every config)."""
    return _tracking(list(_tracked_rows(config, logs, wins, extra_vel_noise_mps, replicate)))


def thrust_mse(
    config: SimConfig,
    logs: Sequence[FlightLog],
    wins: Sequence[Window],
    extra_vel_noise_mps: np.ndarray | None = None,
    above: float = math.inf,
) -> float:
    """``track_thrust(config, logs, wins, extra_vel_noise_mps).mse()`` [N^2], or ``inf`` as
    soon as the rows tracked so far show it above ``above``: a run's squared deviations from
    its own mean, summed over the rows tracked so far, never exceed those of the whole run, so
    their sum over the runs so far, over all rows to come, is a lower bound of the mean square
    that only grows (a search that needs only the least of several configs stops tracking one
    that can no longer be it)."""
    n_rows = sum(max(w.stop - 1 - w.anchor, 0) for w in wins)
    rows = []
    done_n2, run, count, mean, dev_n2 = 0.0, None, 0, 0.0, 0.0
    for row in _tracked_rows(config, logs, wins, extra_vel_noise_mps, 0):
        if row[3] != run:  # a new run: Welford's running mean and squared deviations restart
            done_n2, run, count, mean, dev_n2 = done_n2 + dev_n2, row[3], 0, 0.0, 0.0
        err = row[0] - row[1]
        count += 1
        step = err - mean
        mean += step / count
        dev_n2 += step * (err - mean)
        if (done_n2 + dev_n2) / n_rows > above:
            return math.inf
        rows.append(row)
    return _tracking(rows).mse()


def _tracking(rows: list[tuple[float, float, int, int]]) -> ThrustTracking:
    """The :class:`ThrustTracking` of rows (sim thrust, logged thrust, window, run)."""
    sim, meas, win, run = zip(*rows, strict=True) if rows else ((), (), (), ())
    return ThrustTracking(np.array(sim), np.array(meas), np.array(win, int), np.array(run, int))


def _tracked_rows(
    config: SimConfig,
    logs: Sequence[FlightLog],
    wins: Sequence[Window],
    extra_vel_noise_mps: np.ndarray | None,
    replicate: int,
) -> Iterator[tuple[float, float, int, int]]:
    """(simulated thrust [N], logged thrust [N], window, run) of each row :func:`track_thrust`
    compares, in row order."""
    template = sim_anchor.hovering_template(config)
    for i, log in enumerate(logs):
        row_window = np.full(log.n_rows, -1)
        for k, w in enumerate(wins):
            if w.log_index == i:
                row_window[w.anchor : w.stop - 1] = k
        if not np.any(row_window >= 0):
            continue
        a = LogArrays.of(log)
        if extra_vel_noise_mps is not None:
            a = a.with_velocity_noise(extra_vel_noise_mps, SIMEX_SEED + 1000 * replicate + i)
        for k, (run_start, run_stop) in enumerate(airborne_runs(log)):
            if not np.any(row_window[run_start:run_stop] >= 0):
                continue
            follower = sim_anchor.fresh_copy(template)
            follower.anchor(a.anchor(run_start, lead=False), integral="reset")
            stop = run_start + int(np.flatnonzero(row_window[run_start:run_stop] >= 0)[-1]) + 1
            lead_stop = min(int(np.searchsorted(a.t, a.t[run_start] + LEAD_IN_S)), stop)
            for j in range(run_start, lead_stop):
                follower.set_velocity_setpoint(a.setpoint[j])
                match = a.thrust[j] > 0.0
                follower.anchor(a.anchor(j, True), integral="match_thrust" if match else "keep")
                follower.advance(a.t[j + 1] - a.t[j])
                if row_window[j] >= 0:
                    yield follower.thrust_n, a.thrust[j + 1], row_window[j], 1000 * i + k
            # after the lead-in in chunks: a search that stops reading stops flying soon after
            for chunk in range(lead_stop, stop, TRACKED_CHUNK_ROWS):
                rows = range(chunk, min(chunk + TRACKED_CHUNK_ROWS, stop))
                legs = follower.stream_setpoints(
                    [a.setpoint[j] for j in rows],
                    np.diff(a.t[rows.start : rows.stop + 1]),
                    [a.anchor(j, False) for j in rows],
                )
                for j, thrust_n in zip(rows, legs.thrust_n.tolist(), strict=True):
                    if row_window[j] >= 0:
                        yield thrust_n, a.thrust[j + 1], row_window[j], 1000 * i + k


def thrust_noise_var(logs: Sequence[FlightLog]) -> float:
    """Variance of the white part of the logged thrust [N^2] over the airborne runs."""
    parts, seg = [], []
    for i, log in enumerate(logs):
        for k, (a, b) in enumerate(airborne_runs(log)):
            parts.append(log["thrust_n"][a:b])
            seg.append(np.full(b - a, 1000 * i + k))
    if not parts:
        return 0.0
    return float(white_noise_std(np.concatenate(parts), np.concatenate(seg))[0] ** 2)


def select_thrust_response(
    config: SimConfig,
    logs: Sequence[FlightLog],
    train: Sequence[Window],
    test: Sequence[Window],
    vel_noise_mps: np.ndarray,
    names: Sequence[str] = THRUST_RESPONSE_CAUSES,
) -> tuple[list[Cause], list[Cause]]:
    """Forward selection over ``names`` (of :data:`THRUST_RESPONSE_CAUSES`) by the thrust
    response: each is fitted on top of ``config`` and judged against the others of its round
    (:func:`judge`); of those that pass, the one that leaves the least held-out error is kept
    and the others are fitted again on top of it. (named, not named)."""
    named: list[Cause] = []
    left = list(names)
    before = HeldOut.of(config, logs, test, vel_noise_mps)
    while left:
        fits = [
            fit_thrust_response(n, config, logs, train, test, vel_noise_mps, before) for n in left
        ]
        judged = judge(fits, config.mass_kg, thrust_noise_var(logs))
        ok = [(fit, cause) for fit, (cause, is_named) in zip(fits, judged, strict=True) if is_named]
        if not ok:
            return named, [cause for cause, _ in judged]
        best, cause = min(ok, key=lambda fc: fc[0].after.mse())
        named.append(cause)
        config = with_cause(config, best.name, best.value)
        before = best.after  # the held-out errors of that config: the next round's start
        left.remove(best.name)
    return named, []


def fit_thrust_response(
    name: str,
    config: SimConfig,
    logs: Sequence[FlightLog],
    train: Sequence[Window],
    test: Sequence[Window],
    vel_noise_mps: np.ndarray,
    before: HeldOut | None = None,
) -> ThrustFit:
    """``name`` (one of :data:`THRUST_RESPONSE_CAUSES`) fitted on top of ``config`` to the
    thrust response on ``train`` (the SIMEX-corrected mean squared error), with its held-out
    errors on ``test``. ``vel_noise_mps`` (3,): the log's white velocity noise [m/s], which the
    SIMEX correction adds once more. ``before``: ``HeldOut.of(config, ...)`` if at hand."""
    param, grid = search_grid(name)
    extra = np.asarray(vel_noise_mps, float)

    def train_mse(value: float, above: float = math.inf) -> float:
        """The SIMEX training error ``2 once - twice`` [N^2] (``inf`` once above ``above``)."""
        cfg = with_cause(config, name, value)
        twice = thrust_mse(cfg, logs, train, extra)
        return 2.0 * thrust_mse(cfg, logs, train, above=(above + twice) / 2.0) - twice

    # Every grid value's error, ``inf`` for those that cannot be the least (as in
    # ``command_path._grid_rmse``, whose order they are tried in): the least and where it is
    # are those of the full errors; a margin of 1e-9 keeps values within rounding in full.
    scores = np.full(len(grid), np.inf)
    least = math.inf
    for k in grid_order(name):
        scores[k] = train_mse(grid[k], least + 1e-9 * abs(least))
        least = min(least, scores[k])
    k = int(np.argmin(scores))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    best, best_score = float(grid[k]), scores[k]
    sol = minimize_scalar(train_mse, bounds=(lo, hi), method="bounded", options={"maxiter": 8})
    if sol.fun < best_score:
        best = float(sol.x)
    if before is None:
        before = HeldOut.of(config, logs, test, extra)
    after = HeldOut.of(with_cause(config, name, best), logs, test, extra)
    at_bound = bool(best >= grid[-1] * (1.0 - 1e-3) or best <= grid[0] * (1.0 + 1e-3))
    return ThrustFit(name, param, best, at_bound, before, after)


def judge(
    fits: Sequence[ThrustFit], mass_kg: float, thrust_noise_var_n2: float
) -> list[tuple[Cause, bool]]:
    """Each of ``fits`` (one round: fitted on top of the same config) as a cause with its
    evidence and statistic, and whether it is named (the rules in the module docstring).

    The floor is the logged thrust's white noise (plus its standard errors) but never above the
    least held-out error a fit of the round reaches: a held-out error is an estimate of at
    least the floor, so a floor above it is an estimate too high (seen: on a flight with a
    thrust curve of gain 0.83 and 3.4 % thrust noise, 0.224 N^2 left with the true gain against
    a floor of 0.268 N^2, the SIMEX correction's own scatter), which would leave nothing
    explainable."""
    if not fits:
        return []
    before = fits[0].before
    n_rows = len(before.sq_error)
    margin = FLOOR_MARGIN_SE * NOISE_VAR_REL_SE_SQRT_N / np.sqrt(max(n_rows, 1))
    floor = min(thrust_noise_var_n2 * (1.0 + margin), min(f.after.mse() for f in fits))
    explainable = before.mse() - floor
    least_n = MIN_THRUST_FRACTION * mass_kg * GRAVITY_MPS2
    out = []
    for fit in fits:
        removed = before.mse() - fit.after.mse()
        fraction = removed / explainable if explainable > 0.0 else 0.0
        sig = block_bootstrap(before.sq_error, fit.after.sq_error, before.tracking.window)
        change = np.abs(fit.after.tracking.sim_thrust_n - before.tracking.sim_thrust_n)
        acting = int(np.count_nonzero(change > 1e-9 * max(float(change.max(initial=0.0)), 1e-300)))
        enough = n_rows * removed >= acting * least_n**2
        named = fraction >= MIN_GAIN_FRACTION and sig.p_value <= MAX_P_VALUE and enough
        named = named and not fit.at_bound
        notes = " at the bound (search wider / the cause may be another)" if fit.at_bound else ""
        if not enough:
            notes += f"; removes less than the least thrust ({least_n:.3f} N RMS)"
        evidence = (
            f"held-out one-row-ahead thrust RMSE at no velocity noise (SIMEX) "
            f"{_rms(before.mse())} -> {_rms(fit.after.mse())} N (floor {_rms(floor)} N, the "
            f"logged thrust's noise {_rms(thrust_noise_var_n2)} N; {100 * fraction:.0f} % of "
            f"the explainable removed, p {sig.p_value:.3g}){notes}"
        )
        cause = Cause(
            fit.name,
            {fit.param: fit.value},
            float(fraction),
            float(max(0.0, removed / before.mse())) if before.mse() > 0.0 else 0.0,
            evidence,
            sig.as_dict(),
            fit.at_bound,
        )
        out.append((cause, bool(named)))
    return out


def _rms(mse: float) -> str:
    """An RMS [N] from a mean square that SIMEX may have left slightly negative."""
    return f"{np.sign(mse) * np.sqrt(abs(mse)):.3f}"
