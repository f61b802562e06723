"""`study`: [Kulathunga23]'s residual-learning experiment and [Ostafew16]'s trials, in simulation.

    study [--out out/study] [--trajectories 20] [--repeats 3] [--trials 6] [--m 30]
          [--workers 2] [--vehicle iris_study] [--learned-model first_order_lag|kinematic_4dof]
          [--features state_input|velocity] [--seed 0] [--compile] [--quick]

The nominal planner is [Kulathunga23]'s kinematic NMPC. The learned model is, by default, a
first-order velocity lag whose time constants are identified from the nominal flights plus a
sparse GP on what is left; ``--learned-model kinematic_4dof --features velocity`` is paper
000's setup (the GP alone).

Flies every flight in process (lockstep, deterministic, seeded) on ``--workers`` processes and
writes OUT/report.md with PNG plots and the fitted model files. Progress goes to stderr; the
headline figures are printed on stdout. Exit code 0 on success, 2 with a one-line reason on
bad input.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from companion.nmpc_planner import MULTIROTOR_MODELS
from experiments.study.config import STUDY_VEHICLE, StudyConfig
from experiments.study.run import run_study
from gp.features import FEATURE_SETS
from vehicle_sim.effects.base import SimConfigError


def parse_args(argv: list[str] | None) -> StudyConfig:
    """Command line -> StudyConfig (argparse exits with code 2 on bad options)."""
    parser = argparse.ArgumentParser(prog="study", description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/study"), help="output folder")
    parser.add_argument("--trajectories", type=int, default=20, help="random trajectories")
    parser.add_argument("--repeats", type=int, default=3, help="flights per trajectory")
    parser.add_argument("--trials", type=int, default=6, help="trials on the repeated path")
    parser.add_argument("--m", type=int, default=30, help="inducing points per output")
    parser.add_argument("--workers", type=int, default=2, help="processes flying in parallel")
    parser.add_argument("--vehicle", default=STUDY_VEHICLE, help="simulator preset or config")
    parser.add_argument(
        "--learned-model",
        choices=MULTIROTOR_MODELS,
        default="first_order_lag",
        help="nominal model under the learned residual",
    )
    parser.add_argument("--features", choices=list(FEATURE_SETS), default="state_input")
    parser.add_argument("--seed", type=int, default=0, help="trajectory generator seed")
    parser.add_argument(
        "--compile",
        action="store_true",
        help="compile each augmented planner to C (minutes and gigabytes per model)",
    )
    parser.add_argument("--quick", action="store_true", help="small smoke version")
    args = parser.parse_args(argv)
    try:
        config = StudyConfig(
            out_dir=args.out,
            vehicle=args.vehicle,
            n_trajectories=args.trajectories,
            repeats=args.repeats,
            n_trials=args.trials,
            m=args.m,
            workers=args.workers,
            trajectory_seed=args.seed,
            learned_model=args.learned_model,
            features=args.features,
            compile_augmented=args.compile,
        )
    except ValueError as exc:
        parser.error(str(exc))
    return config.quick() if args.quick else config


def main(argv: list[str] | None = None) -> int:
    """Run the study; returns the exit code."""
    args_list = sys.argv[1:] if argv is None else list(argv)
    if any(a == "--regime" or a.startswith("--regime=") for a in args_list):
        from scripts import rover  # [Ostafew16] on its own robots: study --regime rover_exp1

        return rover.main(args_list)
    try:
        config = parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    start = time.perf_counter()

    def progress(message: str) -> None:
        print(
            f"study [{time.perf_counter() - start:6.1f} s] {message}", file=sys.stderr, flush=True
        )

    try:
        _check_inputs(config)
        result = run_study(config, progress)
    except (SimConfigError, ValueError) as exc:
        print(f"study: error: {exc}", file=sys.stderr)
        return 2
    for name, value in result.headline.items():
        print(f"{name} = {value:.4f}")
    print(f"report: {result.report_path}")
    return 0


def _check_inputs(config: StudyConfig) -> None:
    """Fail before flying: the vehicle must load, the features must suit the model."""
    from companion.nmpc_planner import check_feature_set
    from vehicle_sim import load_sim_config

    load_sim_config(config.vehicle)
    check_feature_set(config.features, config.learned_model)


if __name__ == "__main__":
    sys.exit(main())
