"""`study`: [Kulathunga23]'s residual-learning experiment and [Ostafew16]'s trials, in simulation.

    study [--out out/study] [--trajectories 20] [--repeats 3] [--trials 6] [--m 30]
          [--workers 2 | --scheduler tcp://HOST:8786] [--vehicle iris_study]
          [--learned-model first_order_lag|kinematic_4dof|px4_velocity_pi]
          [--features velocity|state_input|velocity_history|...] [--seed 0] [--compile]
          [--regime paper000|agile|wind_field] [--refit-rounds N] [--no-closed-loop-check]
          [--quick]
    study --regime rover_exp1|rover_exp2|rover_exp3|example [--out DIR] [--trials N]
          [--seed S] [--quick]

``--regime`` picks the task (experiments.study.regimes, physics written down there):
[Kulathunga23]'s low-speed task (default), an agile task at up to 6 m/s, or repeated paths
through a wind field; ``--vehicle`` and ``--features`` override the regime's. The rover
regimes are [Ostafew16]'s three experiments and its section 3.4 example, run as
``python -m scripts.rover`` runs them (``study --regime rover_exp1 --help``).

The nominal planner is [Kulathunga23]'s kinematic NMPC. The learned model is, by default, a
first-order velocity lag whose time constants are identified from the nominal flights plus a
sparse GP on what is left; ``--learned-model kinematic_4dof --features velocity`` is paper
000's setup (the GP alone).

Flies every flight in process (lockstep, deterministic, seeded) on ``--workers`` local processes,
or on the workers of a Dask cluster with ``--scheduler`` (same figures either way), and writes
OUT/report.md with PNG plots and the fitted model files (``--trials 0``: without
[Ostafew16]'s trial-to-trial view, which flies in a process of its own beside the rest).
Progress goes to stderr; the headline figures are printed on stdout, then, when the learned
model's structure flew alone, ``structure_model = NAME``: the model its ``*identified_lag*``
figures flew (first_order_lag, px4_velocity_pi). Exit code 0 on success, 2 with a one-line
reason on bad input, 130 on Ctrl-C and 143 on SIGTERM (its worker processes stopped, nothing
written).
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from dataclasses import replace
from pathlib import Path

from experiments.study.config import StudyConfig
from experiments.study.regimes import REGIMES, with_regime
from flightlog.atomic_output import OutputError, check_writable_dir
from gp.feature_sets import FEATURE_SETS
from planners.model_names import MULTIROTOR_MODELS
from scripts.one_line_parser import OneLineParser, output_path
from scripts.rover import REGIMES as ROVER_REGIMES
from vehicle_sim.effects.base import SimConfigError


def parse_args(argv: list[str] | None) -> StudyConfig:
    """Command line -> StudyConfig (argparse exits with code 2 on bad options)."""
    parser = OneLineParser(
        prog="study",
        description=__doc__.splitlines()[0],
        epilog="Exit codes: 0 done, 2 bad input, 130 stopped by Ctrl-C and 143 by SIGTERM "
        "(nothing written).",
    )
    parser.add_argument("--out", type=output_path, default=Path("out/study"), help="output folder")
    parser.add_argument("--trajectories", type=int, help="random trajectories (default 20)")
    parser.add_argument("--repeats", type=int, help="flights per trajectory (default 3)")
    parser.add_argument(
        "--trials",
        type=int,
        help="trials on the repeated path (default 6; 0: no trial-to-trial view, also with "
        "--quick)",
    )
    parser.add_argument(
        "--m", type=int, help="inducing points per output (default 30, or the regime's)"
    )
    parser.add_argument("--workers", type=int, default=2, help="processes flying in parallel")
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="fly on a Dask cluster's workers (e.g. tcp://10.0.0.5:8786) instead of local "
        "processes; needs pip install 'residual-companion[cluster]' here and on every worker",
    )
    parser.add_argument("--vehicle", default=None, help="simulator preset or config")
    parser.add_argument(
        "--learned-model",
        choices=MULTIROTOR_MODELS,
        default="first_order_lag",
        help="nominal model under the learned residual",
    )
    parser.add_argument("--features", choices=list(FEATURE_SETS), default=None)
    parser.add_argument(
        "--regime",
        choices=[*REGIMES, *ROVER_REGIMES],
        default="paper000",
        help="the multirotor task (default paper000); "
        f"{', '.join(ROVER_REGIMES)}: [Ostafew16]'s rover experiments, with their own options "
        "(study --regime rover_exp1 --help)",
    )
    parser.add_argument(
        "--refit-rounds",
        type=int,
        default=None,
        help="refits on augmented flights of the training seeds (default: the regime's)",
    )
    parser.add_argument(
        "--closed-loop-check",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="fly the model that would fly on the training seeds first and refuse it if it "
        "tracks worse there than the model it replaces (default: on)",
    )
    parser.add_argument("--seed", type=int, default=0, help="trajectory generator seed")
    parser.add_argument(
        "--compile",
        action="store_true",
        help="compile the symbolic linearisation to C (not used by the default one)",
    )
    parser.add_argument("--quick", action="store_true", help="small smoke version")
    args = parser.parse_args(argv)
    try:
        config = StudyConfig(
            out_dir=args.out,
            workers=args.workers,
            scheduler=args.scheduler,
            trajectory_seed=args.seed,
            learned_model=args.learned_model,
            compile_augmented=args.compile,
        )
        config = with_regime(config, args.regime)
        if args.vehicle is not None:
            config = replace(config, vehicle=args.vehicle)
        if args.features is not None:
            config = replace(config, features=args.features)
        if args.refit_rounds is not None:
            config = replace(config, refit_rounds=args.refit_rounds)
        if not args.closed_loop_check:
            config = replace(config, closed_loop_check=False)
        sizes = {field: getattr(args, opt) for opt, field in _SIZE_OPTIONS.items()}
        given = {field: value for field, value in sizes.items() if value is not None}
        config = replace(config, **given)  # after the regime: an explicit --m wins over its m
        no_trials = given.get("n_trials") == 0  # turns a view off: not a size, --quick takes it
        sized = [f for f in given if not (no_trials and f == "n_trials")]
        if args.quick and sized:
            named = ", ".join(f"--{o}" for o, f in _SIZE_OPTIONS.items() if f in sized)
            parser.error(f"--quick sets the study's sizes itself; drop --quick or {named}")
    except ValueError as exc:
        parser.error(str(exc))
    if args.quick:
        return replace(config.quick(), n_trials=0) if no_trials else config.quick()
    return config


# the study's sizes on the command line: option -> StudyConfig field
_SIZE_OPTIONS = {
    "trajectories": "n_trajectories",
    "repeats": "repeats",
    "trials": "n_trials",
    "m": "m",
}


def _rover_regime(args: list[str]) -> bool:
    """True when ``--regime`` names one of the rover regimes (scripts.rover), which have their
    own CLI; the multirotor regimes (experiments.study.regimes) and bad names stay here."""
    for i, arg in enumerate(args):
        value = arg.split("=", 1)[1] if arg.startswith("--regime=") else None
        if arg == "--regime" and i + 1 < len(args):
            value = args[i + 1]
        if value is not None:
            return value in ROVER_REGIMES
    return False


def main(argv: list[str] | None = None) -> int:
    """Run the study; returns the exit code."""
    args_list = sys.argv[1:] if argv is None else list(argv)
    if _rover_regime(args_list):
        from scripts import rover  # [Ostafew16] on its own robots: study --regime rover_exp1

        return rover.main(args_list, prog="study")
    try:
        config = parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    start = time.perf_counter()

    def progress(message: str) -> None:
        print(
            f"study [{time.perf_counter() - start:6.1f} s] {message}", file=sys.stderr, flush=True
        )

    previous_term = signal.signal(signal.SIGTERM, _terminate)
    try:
        _check_inputs(config)
        # the flights' and the fits' libraries (scikit-learn, Matplotlib, Dask: about 3 s of
        # CPU) load once the command line is read: --help and a bad option answer sooner
        from experiments.study.run import run_study

        result = run_study(config, progress)
    except (SimConfigError, ValueError) as exc:
        print(f"study: error: {exc}", file=sys.stderr)
        return 2
    except OutputError as exc:
        print(f"study: error: --out {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # its workers are stopped (experiments.executors)
        how, code = ("SIGTERM", 143) if isinstance(exc, _Terminated) else ("Ctrl-C", 130)
        print(
            f"study: stopped by {how}; nothing written to {config.out_dir} (the report and "
            "its models appear only when the study completes)",
            file=sys.stderr,
        )
        return code
    finally:
        signal.signal(signal.SIGTERM, previous_term)
    for name, value in result.headline.items():
        print(f"{name} = {value:.4f}")
    if result.paper000.structure_model is not None:
        print(f"structure_model = {result.paper000.structure_model}")
    print(f"report: {result.report_path}")
    return 0


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the study like Ctrl-C so that its worker processes are stopped with
    it instead of flying on without it."""


def _terminate(_signum: int, _frame: object) -> None:
    raise _Terminated


def _check_inputs(config: StudyConfig) -> None:
    """Fail before flying: the vehicle must load, the features must suit the model."""
    from companion.nmpc_planner import check_feature_set
    from vehicle_sim import load_sim_config

    load_sim_config(config.vehicle)
    check_feature_set(config.features, config.learned_model)
    check_writable_dir(config.out_dir)


if __name__ == "__main__":
    sys.exit(main())
