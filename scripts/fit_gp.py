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

import math
import sys
from dataclasses import dataclass
from pathlib import Path

from gp.feature_sets import FEATURE_SETS
from gp.inducing import STRATEGIES
from gp.training_config import TrainingConfig
from planners.model_names import MULTIROTOR_MODELS
from scripts.one_line_parser import OneLineParser, output_path

EXIT_DOUBTFUL = 3
EXIT_INTERRUPTED = 130
DEFAULTS = TrainingConfig()


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
        default=DEFAULTS.features,
        choices=list(FEATURE_SETS),
        help="the GP's inputs (default %(default)s, [Kulathunga23]'s)",
    )
    parser.add_argument(  # the unicycle is the ground robots' model, learned by experiments.rover
        "--nominal",
        default=DEFAULTS.nominal,
        choices=MULTIROTOR_MODELS,
        help="the model the GP corrects (default %(default)s, [Kulathunga23]'s; "
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
        default=DEFAULTS.inducing,
        choices=list(STRATEGIES),
        help="where the inducing points go (default %(default)s)",
    )
    parser.add_argument(
        "--m", type=int, default=DEFAULTS.m, help="number of inducing points (default %(default)s)"
    )
    parser.add_argument("--optimize-inducing", action="store_true", help="refine positions")
    parser.add_argument(
        "--seed", type=int, default=DEFAULTS.seed, help="random seed (default %(default)s)"
    )
    parser.add_argument(
        "--holdout-fraction",
        type=float,
        default=DEFAULTS.holdout_fraction,
        help="share of the rows held out to evaluate the fit (default %(default)s)",
    )
    parser.add_argument(
        "--restarts",
        type=int,
        default=DEFAULTS.restarts,
        help="starting points of the hyperparameter optimisation (default %(default)s)",
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
        if value is not None and not 0 < value < math.inf:
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
    if args.out.is_dir():  # diagnose --out takes a folder; this one names a file
        parser.error(
            f"--out {args.out} is a folder; give the model file's name, e.g. --out "
            f"{args.out / 'model'} (writes model.npz and its plots there)"
        )
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


def main(argv: list[str] | None = None) -> int:
    """Run fit-gp; returns the exit code (0 ok, 1 model refused by its check, 2 bad input, 3
    model doubtful and not written, 130 Ctrl-C)."""
    try:
        config = parse_args(argv)
    except SystemExit as exc:  # --help (0) or a bad argument (2, message already printed)
        return int(exc.code or 0)
    written: list[Path] = []
    try:
        # the fitting and its libraries (scikit-learn, SciPy, CasADi, Matplotlib, pyulog: about
        # 3 s of CPU) load once the command line is read: --help and a bad option answer at once
        from scripts.fit_gp_run import fit

        return fit(config, written)
    except KeyboardInterrupt:
        kept = f"; wrote {', '.join(map(str, written))} before it" if written else ""
        print(f"fit-gp: stopped by Ctrl-C{kept or '; no model written'}", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
