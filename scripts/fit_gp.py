"""fit-gp: learn a residual model from flight logs.

    fit-gp LOGS... --out MODEL [--features velocity|state_input|history]
           [--nominal kinematic_4dof|first_order_lag] [--nominal-param residual_dt_s=0.05]
           [--inducing low_speed|cluster|random] [--m 30] [--optimize-inducing]
           [--seed 0] [--holdout-fraction 0.2] [--restarts 3] [--mode offboard] [--no-plots]
           [--check-horizon-s 2.0] [--residual-interval-s 0.1]

With ``--check-horizon-s``, a quarter of the logs (or of each log) is held out and the model's
position prediction over that horizon (the NMPC's N x dt) is compared with [Kulathunga23]'s
kinematic model's; a model that does not beat it is refused in one line (exit code 1, no model
written; gp.prediction_check).

With ``--nominal first_order_lag`` and no ``--nominal-param tau_s=...``, the velocity loop's
time constants are identified from the logs first (least squares, gp.lag_identification) and
the GP learns what the identified lag leaves; the model file records them.

``--residual-interval-s`` measures the residual over that interval, a whole number of the logs'
steps (default: one step, [Kulathunga23]'s one-step residual). The NMPC applies the residual
constant over its 0.1 s interval; `study` learns over it, and ``--features velocity_history``
needs it (its lag is one interval, which the companion checks).

Logs of different vehicles or configs (their metadata disagree on the simulator preset,
mass, PX4 airframe, board or velocity-loop gains: flightlog.vehicle_identity) are pooled as
given, with a one-line warning naming the logs and the field.
A GP that explains nothing but noise on some axis (signal variance under 1 % of the noise
variance: it predicts about 0 there; gp.noise_optimum) is said in a one-line warning too, and
so is training data (the ``--mode`` rows) spanning less than a second of flight per inducing
point: fly or log more, or lower ``--m``.

Writes MODEL.npz (one self-describing file) and MODEL_residual_{n,e,d}.png, prints the
held-out nominal and augmented RMSE per axis ([Kulathunga23], Table 2) on stdout; progress goes
to stderr. Exit code 0 on success, 1 when the prediction check refuses the model, 2 with a
one-line reason on bad input, 3 when the model is worse than nominal on held-out rows or a
time constant sits on its bound (not written unless ``--force``), 130 on Ctrl-C (one line
saying what was written before it).
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, replace
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
from gp.features import FEATURE_SETS
from gp.inducing import STRATEGIES
from gp.lag_identification import TAU_BOUNDS_S
from gp.model_io import ResidualModel, model_path, save_model
from gp.plots import plot_residuals
from gp.prediction_check import refusal
from gp.residual_interval import log_step_s, mixed_steps, residual_steps
from gp.training import TrainingConfig, train_residual_model
from planners.nominal_models import MODELS
from scripts.one_line_parser import OneLineParser, output_path


@dataclass(frozen=True)
class FitGpConfig:
    """Parsed command line: the logs, where to write, and the training settings."""

    logs: tuple[Path, ...]
    out: Path
    training: TrainingConfig
    plots: bool = True
    force: bool = False
    residual_interval_s: float | None = None


def parse_args(argv: list[str] | None) -> FitGpConfig:
    """Parse the command line into a FitGpConfig (exits with code 2 on bad arguments)."""
    parser = OneLineParser(
        prog="fit-gp",
        description="Fit a sparse-GP residual model from flight logs.",
        epilog="Exit codes: 0 written, 1 refused by --check-horizon-s (worse than the model it "
        "would replace), 2 bad input, 3 not written: worse than nominal or a time constant on "
        "its bound (--force writes it), 130 stopped by Ctrl-C.",
    )
    parser.add_argument(
        "logs", nargs="+", type=Path, help="flight logs: schema-v1 CSV or PX4 ULog (.ulg)"
    )
    parser.add_argument("--out", required=True, type=output_path, help="model file (MODEL.npz)")
    parser.add_argument(
        "--features",
        default="velocity",
        choices=list(FEATURE_SETS),
        help="the GP's inputs (default velocity, [Kulathunga23]'s)",
    )
    parser.add_argument(  # the unicycle is the ground robots' model, learned by experiments.rover
        "--nominal",
        default="kinematic_4dof",
        choices=[m for m in MODELS if m != "unicycle"],
        help="the model the GP corrects (default kinematic_4dof, [Kulathunga23]'s; "
        "first_order_lag: the velocity loop's lag, identified from the logs)",
    )
    parser.add_argument(
        "--nominal-param",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="nominal model parameter (repeatable), e.g. residual_dt_s=0.05",
    )
    parser.add_argument(
        "--inducing",
        default="low_speed",
        choices=list(STRATEGIES),
        help="where the inducing points go (default low_speed)",
    )
    parser.add_argument("--m", type=int, default=30, help="number of inducing points (default 30)")
    parser.add_argument("--optimize-inducing", action="store_true", help="refine positions")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--holdout-fraction",
        type=float,
        default=0.2,
        help="share of the rows held out to evaluate the fit (default 0.2)",
    )
    parser.add_argument(
        "--restarts",
        type=int,
        default=3,
        help="starting points of the hyperparameter optimisation (default 3)",
    )
    parser.add_argument(
        "--mode",
        action="append",
        default=None,
        help="keep only rows in this flight mode (e.g. offboard; repeatable)",
    )
    parser.add_argument(
        "--no-plots", action="store_true", help="do not write MODEL_residual_{n,e,d}.png"
    )
    parser.add_argument(
        "--check-horizon-s",
        type=float,
        default=None,
        help="check the multi-step prediction over this horizon on held-out logs first",
    )
    parser.add_argument(
        "--residual-interval-s",
        type=float,
        default=None,
        help="measure the residual over this interval [s] (the NMPC's 0.1 s; default one log step)",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="write the model even if it is worse than nominal or a time constant is on its bound",
    )
    args = parser.parse_args(argv)
    for option, value in (
        ("--residual-interval-s", args.residual_interval_s),
        ("--check-horizon-s", args.check_horizon_s),
    ):  # inf passes "> 0" and then cannot become a number of log steps
        if value is not None and not 0 < value < np.inf:
            parser.error(f"{option} must be finite and > 0 s, got {value}")
    params = []
    for item in args.nominal_param:
        name, sep, value = item.partition("=")
        try:
            params.append((name, float(value)))
        except ValueError:
            sep = ""
        if not sep:
            parser.error(f"--nominal-param {item!r}: expected NAME=NUMBER")
    if args.m < 1:
        parser.error(f"--m must be >= 1, got {args.m}")
    if args.seed < 0:
        parser.error(f"--seed must be >= 0, got {args.seed}")
    if args.restarts < 1:
        parser.error(f"--restarts must be >= 1 starting point(s), got {args.restarts}")
    if not 0.0 < args.holdout_fraction < 1.0:
        parser.error(f"--holdout-fraction must be in (0, 1), got {args.holdout_fraction}")
    training = TrainingConfig(
        features=args.features,
        nominal=args.nominal,
        nominal_params=tuple(sorted(params)),
        inducing=args.inducing,
        m=args.m,
        optimize_inducing=args.optimize_inducing,
        restarts=args.restarts,
        holdout_fraction=args.holdout_fraction,
        modes=tuple(m.upper() for m in args.mode) if args.mode else None,
        seed=args.seed,
        check_horizon_s=args.check_horizon_s,
    )
    return FitGpConfig(
        tuple(args.logs),
        args.out,
        training,
        plots=not args.no_plots,
        force=args.force,
        residual_interval_s=args.residual_interval_s,
    )


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


EXIT_DOUBTFUL = 3
EXIT_INTERRUPTED = 130
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


def main(argv: list[str] | None = None) -> int:
    """Run fit-gp; returns the exit code (0 ok, 1 model refused by its check, 2 bad input, 3
    model doubtful and not written, 130 Ctrl-C)."""
    try:
        config = parse_args(argv)
    except SystemExit as exc:  # --help (0) or a bad argument (2, message already printed)
        return int(exc.code or 0)
    written: list[Path] = []
    try:
        return _fit(config, written)
    except KeyboardInterrupt:
        kept = f"; wrote {', '.join(map(str, written))} before it" if written else ""
        print(f"fit-gp: stopped by Ctrl-C{kept or '; no model written'}", file=sys.stderr)
        return EXIT_INTERRUPTED


def _fit(config: FitGpConfig, written: list[Path]) -> int:
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


if __name__ == "__main__":
    sys.exit(main())
