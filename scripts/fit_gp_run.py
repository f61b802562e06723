"""What `fit-gp` (scripts.fit_gp) does once its command line is read: read the logs, fit, check
and write the model, say what to doubt."""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from companion.nmpc_planner import check_residual_model
from companion.runner import RunnerConfig
from flightlog.atomic_output import OutputError, check_writable_file
from flightlog.reader import read_log, require_distinct, require_modes, require_rates
from flightlog.schema import FlightLogError
from flightlog.ulog import damage_note, rows_left_out_note
from flightlog.vehicle_identity import mixed_vehicle_fields
from gp.datasets import ResidualDataset
from gp.errors import DatasetError, GPInputError, ModelFileError
from gp.lag_identification import TAU_BOUNDS_S
from gp.model_io import ResidualModel, model_path, save_model
from gp.plots import plot_residuals
from gp.prediction_check import refusal
from gp.residual_interval import log_step_s, mixed_steps, residual_steps
from gp.training import train_residual_model
from scripts.fit_gp import EXIT_DOUBTFUL, FitGpConfig

# The least training data a fit is quiet about, in seconds of flight per inducing point. Time,
# not rows: rows logged within the velocity loop's time constant of each other (fit-gp
# --nominal first_order_lag identifies it: 0.69 s on the simulated Iris's square mission) see about
# the same velocity, so a log at five times the rate has five times the rows and no more to
# learn from. A second of flight gives a sample or two of the residual that the last did not;
# with fewer than one per inducing point, some points sit where no data pins them down and the
# GP learns the few manoeuvres it saw. 30 s at the default --m 30.
MIN_FLIGHT_S_PER_INDUCING = 1.0


def too_little_data(train: ResidualDataset, m: int, modes: tuple[str, ...] | None) -> str | None:
    """One line when the training rows (those of ``modes``; None: all) span less flight than
    MIN_FLIGHT_S_PER_INDUCING [s] per inducing point (``m``), else None."""
    flown_s = float(np.sum(train.dt_s)) / train.features.residual_steps  # each row's own step
    if flown_s >= MIN_FLIGHT_S_PER_INDUCING * m:
        return None
    where = f" in {'/'.join(modes)}" if modes else ""
    most = int(flown_s / MIN_FLIGHT_S_PER_INDUCING)
    lower = f"lower --m (to {most} or fewer)" if most >= 1 else "lower --m"
    return (
        f"{flown_s:.1f} s of flight{where} to train on ({train.n_rows} rows) for {m} inducing "
        f"points, under {MIN_FLIGHT_S_PER_INDUCING:g} s per point: too little to learn the "
        f"residual from; fly/log more, or {lower}"
    )


# Held-out RMSE this much above nominal counts as worse (ties are within the split's noise).
WORSE_MARGIN = 0.02


def model_doubts(
    metrics: dict[str, list[float]], lag: dict[str, object] | None, gp_flies: bool = True
) -> list[str]:
    """Why the fitted model should not be trusted: worse than nominal on held-out rows on
    some axis (by more than WORSE_MARGIN; not asked when ``gp_flies`` is False: the check
    against the structure alone left the GP out, so the structure flies without it), or an
    identified time constant on its search bound (TAU_BOUNDS_S)."""
    doubts = []
    held_out = zip("ned", metrics["nominal_rmse_mps"], metrics["augmented_rmse_mps"], strict=False)
    for axis, nom, aug in held_out if gp_flies else ():
        if aug > nom * (1.0 + WORSE_MARGIN):
            doubts.append(
                f"axis {axis}: held-out RMSE {aug:.4f} m/s with the GP, {nom:.4f} m/s without; "
                "the model is worse than nominal"
            )
    lo, hi = TAU_BOUNDS_S
    for key in ("tau_s", "tau_d_s"):
        tau = None if lag is None else lag.get(key)
        if tau is not None and (tau <= lo * 1.05 or tau >= hi * 0.95):
            doubts.append(
                f"identified {key}={float(tau):.3f} s sits on its bound [{lo:g}, {hi:g}] s; "
                "the logs do not determine it (excite steps in velocity, or pass "
                f"--nominal-param {key}=...)"
            )
    return doubts


def _companion_refusal(model: ResidualModel, period_s: float) -> str | None:
    """Why the companion's NMPC would refuse ``model`` at take-off, flown at a control period
    of ``period_s`` [s] (a velocity history over other than its 0.1 s interval, lagged
    features it cannot carry, a residual over another step), else None: fit-gp also fits
    models for analysis only, so this is said, not enforced."""
    try:
        check_residual_model(model, period_s)
    except ModelFileError as exc:
        return str(exc)
    return None


def fit(config: FitGpConfig, written: list[Path]) -> int:
    """Fit, check and write the model; appends each file written to ``written``; returns the
    exit code."""
    start = time.perf_counter()

    def progress(message: str) -> None:
        print(f"fit-gp [{time.perf_counter() - start:6.1f} s] {message}", file=sys.stderr)

    try:
        require_distinct(config.logs)
        logs = []
        for path in config.logs:
            logs.append(read_log(path))
            require_rates(logs[-1], "fit-gp")
            progress(f"read {path} ({logs[-1].n_rows} rows)")
            for note in (damage_note(logs[-1]), rows_left_out_note(logs[-1])):
                if note:
                    print(f"fit-gp: warning: {note}", file=sys.stderr)
        mixed = mixed_vehicle_fields(logs)
        if mixed:
            print(
                f"fit-gp: warning: the logs are from different vehicles or configs "
                f"({'; '.join(mixed)}); one model learns their mix, which fits each of them "
                "less well: fit each vehicle's logs on their own unless they fly alike",
                file=sys.stderr,
            )
        mixed_rates = mixed_steps(logs)
        if mixed_rates:
            print(f"fit-gp: warning: {mixed_rates}", file=sys.stderr)
        require_modes(logs, config.training.modes)
        check_writable_file(model_path(config.out))  # found now, not after the fit
        training = config.training
        if config.residual_interval_s is not None:
            try:
                steps = residual_steps(logs, config.residual_interval_s)
            except GPInputError as exc:
                raise GPInputError(f"--residual-interval-s: {exc}") from None
            progress(f"residual over {steps} log steps ({config.residual_interval_s:g} s)")
            training = replace(training, residual_steps=steps)
        result = train_residual_model(logs, training, progress)
        little = too_little_data(result.train, training.m, training.modes)
        if little:
            print(f"fit-gp: warning: {little}", file=sys.stderr)
        if result.all_noise is not None:
            print(f"fit-gp: warning: {result.all_noise}", file=sys.stderr)
        if not result.may_fly:
            print(f"fit-gp: {refusal(result.model)}", file=sys.stderr)
            return 1
        lag = result.model.training.get("identified_lag")
        doubts = model_doubts(result.metrics, lag, result.gp_earns_its_place)
        for doubt in doubts:
            print(f"fit-gp: warning: {doubt}", file=sys.stderr)
        if doubts and not config.force:
            print(
                "fit-gp: no model written; fix the data or pass --force to write it anyway",
                file=sys.stderr,
            )
            return EXIT_DOUBTFUL
        if result.flown == "structure":  # said only of a file that is written
            structure = result.model.features.nominal_model
            print(
                f"fit-gp: the GP does not beat {structure} alone (see the check above): the "
                f"companion flies {structure} without it (the file keeps the GP to inspect)",
                file=sys.stderr,
            )
        model_file = save_model(config.out, result.model)
        written.append(model_file)
        progress(f"wrote {model_file}")
        step_s = log_step_s(logs)
        unflyable = _companion_refusal(result.model, step_s)
        if unflyable:
            print(
                f"fit-gp: warning: the companion's NMPC will refuse this model (flown at the "
                f"logs' rate): {unflyable}",
                file=sys.stderr,
            )
        elif _companion_refusal(result.model, 1.0 / RunnerConfig.rate_hz):
            print(
                f"fit-gp: warning: the companion's NMPC will refuse this model at its default "
                f"{RunnerConfig.rate_hz:g} Hz (the residual is measured over the logs' "
                f"{step_s:.3g} s steps): fly it with companion --rate-hz {1.0 / step_s:.3g}, or "
                f"fit logs flown at {RunnerConfig.rate_hz:g} Hz",
                file=sys.stderr,
            )
        if config.plots:
            for png in plot_residuals(result.model, result.test, model_file.with_suffix("")):
                written.append(png)
                progress(f"wrote {png}")
    except (FlightLogError, DatasetError, GPInputError, ModelFileError, ValueError) as exc:
        print(f"fit-gp: error: {exc}", file=sys.stderr)
        return 2
    except OutputError as exc:
        print(f"fit-gp: error: --out {exc}", file=sys.stderr)
        return 2
    print("axis  nominal_rmse_mps  augmented_rmse_mps")
    for axis, nom, aug in zip(
        "ned",
        result.metrics["nominal_rmse_mps"],
        result.metrics["augmented_rmse_mps"],
        strict=False,
    ):
        print(f"{axis:>4}  {nom:16.4f}  {aug:18.4f}")
    return 0
