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
estimator's velocity; a simulated log's noise is added after the flight), and a longer lag
smooths that noise away, which would bias ``tau_s`` up by 20 % or more at 0.03-0.08 m/s. The
fit removes that bias by SIMEX [Cook94]: the squared thrust error is measured once more with
the log's own white velocity noise (:func:`.noise_floor.white_noise_std`) added again, and
extrapolated linearly to no noise, ``2 mse(noise) - mse(2 x noise variance)`` (the same holds
for the thrust curve's gain, which scales that noise too). The command noise in the floor below,
``mse(2 x noise variance) - mse(noise)``, is averaged over ``FLOOR_REPLICATES`` draws of that
extra noise, as [Cook94] average their replicates: one draw scattered by a factor of two between
missions (0.50 vs 0.28 N for the same hidden lag), enough to lift the floor above the error it
is subtracted from. The parameter is
fitted on the training windows' rows and judged on the held-out ones like any cause: named only
if it removes at least ``MIN_GAIN_FRACTION`` of the held-out squared thrust error left above the
floor (the logged thrust's own white noise plus the command noise the velocity noise makes,
both estimated from the log, plus ``FLOOR_MARGIN_SE`` standard errors of that estimate), if
the removal is significant by a block bootstrap over the held-out windows (p <=
``MAX_P_VALUE``), and if it removes at least the least thrust ``MIN_THRUST_FRACTION`` of the
weight in RMS over the rows it acts on (the force causes' least force,
``SelectionConfig.min_force_fraction``).

The least thrust is a floor on the *removed* mean squared error, not on the explainable part:
with sensor noise independent of the cause, ``mse(before) - mse(after)`` estimates the mean
square of the thrust the cause accounts for whatever the noise (the noise cancels in the
difference), so the rule means the same on exact and on noisy logs. The explainable part has no
such floor on an exact log (the noise floor is zero), where the follower's own small mismatch
(it steps once per row; seen: 0.016 N of one-row-ahead thrust RMSE on a 5-minute log) was half
removed by a 21 ms motor lag that was not there: sqrt(0.016^2 - 0.011^2) = 0.012 N removed,
against 0.044 N of least thrust for a 1.5 kg Iris. A true lag removes far more (seen: 0.522
-> 0.447 N at IMU noise 0.3 m/s^2, 0.27 N removed, for tau_s 0.041 s). What it cannot tell
apart is a lag from the few milliseconds by which a named command delay was fitted short (seen
on an exact log: a 24 ms lag removed 0.048 N beside a delay fitted 5 ms short, and was named).

Needs the produced thrust (``thrust_n`` as logged, or from ESC rotor speeds); PX4's normalised
thrust setpoint is the command itself and shows no lag.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from diagnosis import sim_anchor
from diagnosis.cause import Cause
from diagnosis.command_path import search_grid, with_cause
from diagnosis.forces import GRAVITY_MPS2
from diagnosis.noise_floor import NOISE_VAR_REL_SE_SQRT_N, block_bootstrap, white_noise_std
from diagnosis.replay import LEAD_IN_S, LogArrays, Window, airborne_runs
from diagnosis.selection import SelectionConfig
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
FLOOR_REPLICATES = 4  # draws of the extra velocity noise the floor's command noise averages


@dataclass(frozen=True)
class ThrustTracking:
    """One-row-ahead thrust of the anchored follower against the logged thrust.

    Attributes:
        sim_thrust_n, meas_thrust_n: (m,) simulated and logged total rotor thrust [N].
        window: (m,) index (into the windows given) of the window each row belongs to.
    """

    sim_thrust_n: np.ndarray
    meas_thrust_n: np.ndarray
    window: np.ndarray

    def sq_error(self) -> np.ndarray:
        """(m,) squared thrust error per row [N^2]."""
        return (self.sim_thrust_n - self.meas_thrust_n) ** 2

    def mse(self) -> float:
        """Mean squared thrust error [N^2] (nan without rows)."""
        return float(np.mean(self.sq_error())) if len(self.window) else float("nan")


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
    template = sim_anchor.hovering_template(config)
    sim, meas, win = [], [], []
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
        for run_start, run_stop in airborne_runs(log):
            if not np.any(row_window[run_start:run_stop] >= 0):
                continue
            follower = sim_anchor.fresh_copy(template)
            follower.anchor(a.anchor(run_start, lead=False), integral="reset")
            lead_end = a.t[run_start] + LEAD_IN_S
            last = run_start + int(np.flatnonzero(row_window[run_start:run_stop] >= 0)[-1])
            for j in range(run_start, last + 1):
                lead = a.t[j] < lead_end
                follower.set_velocity_setpoint(a.setpoint[j])
                match = lead and a.thrust[j] > 0.0
                follower.anchor(a.anchor(j, lead), integral="match_thrust" if match else "keep")
                state = follower.step(a.t[j + 1] - a.t[j])
                if row_window[j] >= 0:
                    sim.append(state.thrust_n)
                    meas.append(a.thrust[j + 1])
                    win.append(row_window[j])
    return ThrustTracking(np.array(sim), np.array(meas), np.array(win, int))


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
    response: each is fitted on top of ``config``; the named one that removes the largest
    fraction is kept and the others are fitted again on top of it. (named, not named)."""
    named: list[Cause] = []
    left = list(names)
    while left:
        before = track_thrust(config, logs, test)
        fits = [
            fit_thrust_response(n, config, logs, train, test, vel_noise_mps, before) for n in left
        ]
        ok = [cause for cause, is_named in fits if is_named]
        if not ok:
            return named, [cause for cause, _ in fits]
        best = max(ok, key=lambda c: c.explained_fraction)
        named.append(best)
        config = with_cause(config, best.name, next(iter(best.params.values())))
        left.remove(best.name)
    return named, []


def fit_thrust_response(
    name: str,
    config: SimConfig,
    logs: Sequence[FlightLog],
    train: Sequence[Window],
    test: Sequence[Window],
    vel_noise_mps: np.ndarray,
    before: ThrustTracking | None = None,
) -> tuple[Cause, bool]:
    """``name`` (one of :data:`THRUST_RESPONSE_CAUSES`) fitted to the thrust response on
    ``train``, judged on ``test``: (the cause with its evidence and statistic, whether it is
    named). ``vel_noise_mps`` (3,): the log's white velocity noise, which the SIMEX correction
    adds once more. ``before``: ``track_thrust(config, logs, test)`` if already at hand."""
    param, grid = search_grid(name)
    extra = np.asarray(vel_noise_mps, float)

    def train_mse(value: float) -> float:
        cfg = with_cause(config, name, value)
        once = track_thrust(cfg, logs, train).mse()
        twice = track_thrust(cfg, logs, train, extra).mse()
        return 2.0 * once - twice

    scores = [train_mse(v) for v in grid]
    k = int(np.argmin(scores))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    best, best_score = float(grid[k]), scores[k]
    sol = minimize_scalar(train_mse, bounds=(lo, hi), method="bounded", options={"maxiter": 8})
    if sol.fun < best_score:
        best = float(sol.x)
    if before is None:
        before = track_thrust(config, logs, test)
    best_config = with_cause(config, name, best)
    after = track_thrust(best_config, logs, test)
    twice = [track_thrust(best_config, logs, test, extra, r) for r in range(FLOOR_REPLICATES)]
    follower_noise = max(float(np.mean([t.mse() for t in twice])) - after.mse(), 0.0)
    floor = thrust_noise_var(logs) + follower_noise
    margin = FLOOR_MARGIN_SE * NOISE_VAR_REL_SE_SQRT_N / np.sqrt(max(len(before.window), 1))
    explainable = before.mse() - floor * (1.0 + margin)
    removed = before.mse() - after.mse()
    fraction = removed / explainable if explainable > 0.0 else 0.0
    sig = block_bootstrap(before.sq_error(), after.sq_error(), before.window)
    at_bound = bool(best >= grid[-1] * (1.0 - 1e-3) or best <= grid[0] * (1.0 + 1e-3))
    least_n = MIN_THRUST_FRACTION * config.mass_kg * GRAVITY_MPS2
    change = np.abs(after.sim_thrust_n - before.sim_thrust_n)
    acting = int(np.count_nonzero(change > 1e-9 * max(float(change.max(initial=0.0)), 1e-300)))
    enough = len(before.window) * removed >= acting * least_n**2
    named = fraction >= MIN_GAIN_FRACTION and sig.p_value <= MAX_P_VALUE and enough
    named = named and not at_bound
    notes = " at the bound (search wider / the cause may be another)" if at_bound else ""
    if not enough:
        notes += f"; removes less than the least thrust ({least_n:.3f} N RMS)"
    evidence = (
        f"held-out one-row-ahead thrust RMSE {np.sqrt(before.mse()):.3f} -> "
        f"{np.sqrt(after.mse()):.3f} N (floor {np.sqrt(floor):.3f} N: thrust noise "
        f"{np.sqrt(floor - follower_noise):.3f} N and the command noise the velocity noise "
        f"makes; {100 * fraction:.0f} % of the explainable removed, "
        f"p {sig.p_value:.3g}){notes}"
    )
    cause = Cause(
        name,
        {param: best},
        float(fraction),
        float(max(0.0, removed / before.mse())),
        evidence,
        sig.as_dict(),
        at_bound,
    )
    return cause, bool(named)
