"""`diagnose`: show what a simulation config gets wrong about measured flights, and fix it.

    diagnose LOGS... --sim-config FILE|PRESET --out DIR
    diagnose LOGS... --sim-config FILE|PRESET --out DIR --batch [--workers 2 | --scheduler ADDR]

LOGS are schema-v1 CSV flight logs (with their .json sidecars) or PX4 ULog files (.ulg).
Writes DIR/report.json (schema diagnosis/2), DIR/report.md with PNG plots, and
DIR/extended_config.toml (the config plus the accepted effects with fitted parameters).
With ``--batch`` every log is diagnosed on its own (one job each, on ``--workers`` local
processes or on the workers of the Dask cluster at ``--scheduler tcp://HOST:8786``) and DIR
holds one such report set per log, in DIR/<log name>/, plus DIR/batch.json (verdict and gain
per log). A log the batch cannot diagnose (unreadable, too slow a rate, never airborne) is
skipped with one line saying why, here and in batch.json, and the others are diagnosed.
Progress and the report's warnings go to stderr. Exit codes: 0 done, 2 bad input (one line
saying why; in a batch, when no log at all can be diagnosed), 130 stopped by Ctrl-C (one line;
nothing written, since the report set appears whole or not at all).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from experiments.executors import SchedulerError, check_scheduler_address
from scripts.one_line_parser import OneLineParser, output_path

EXIT_OK = 0
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130
DEFAULT_WORKERS = 2  # --batch's local processes


@dataclass(frozen=True)
class DiagnoseArgs:
    """Parsed command line: log files, config path or preset name, output directory."""

    logs: tuple[Path, ...]
    sim_config: str
    out_dir: Path
    batch: bool = False
    workers: int = DEFAULT_WORKERS
    scheduler: str | None = None


def parse_args(argv: list[str] | None) -> DiagnoseArgs:
    parser = OneLineParser(
        prog="diagnose",
        description="Compare a simulation config with measured flight logs, name what it gets "
        "wrong (effect vocabulary), fit it, write report and extended config.",
        epilog="Exit codes: 0 done, 2 bad input, 130 stopped by Ctrl-C (nothing written).",
    )
    parser.add_argument(
        "logs", nargs="+", type=Path, help="schema-v1 flight logs (CSV) or PX4 ULog files (.ulg)"
    )
    parser.add_argument(
        "--sim-config", required=True, help="simulation config TOML file or preset name"
    )
    parser.add_argument("--out", required=True, type=output_path, help="output directory")
    parser.add_argument(
        "--batch", action="store_true", help="diagnose every log on its own (one report each)"
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=None,
        help=f"--batch: local processes (default {DEFAULT_WORKERS})",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="--batch: run the jobs on a Dask cluster (tcp://HOST:PORT) instead of local "
        "processes; needs pip install 'residual-companion[cluster]'",
    )
    args = parser.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")
    for option in ("scheduler", "workers"):
        if getattr(args, option) is not None and not args.batch:
            parser.error(f"--{option} runs a --batch diagnosis; add --batch")
    if args.workers is not None and args.scheduler is not None:
        parser.error("--workers are local processes, --scheduler a cluster's; give one")
    args.workers = DEFAULT_WORKERS if args.workers is None else args.workers
    if args.scheduler is not None:
        try:
            check_scheduler_address(args.scheduler)
        except SchedulerError as exc:
            parser.error(str(exc))
    return DiagnoseArgs(
        tuple(args.logs), args.sim_config, args.out, args.batch, args.workers, args.scheduler
    )


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        # the diagnosis and its libraries (SciPy, Matplotlib, Numba, CasADi: about 3 s of CPU)
        # load once the command line is read: --help and a bad option answer at once
        from scripts.diagnose_run import run_diagnose

        return run_diagnose(args)
    except KeyboardInterrupt:  # the report set is written atomically: none of it is there
        print(f"diagnose: stopped by Ctrl-C; nothing written to {args.out_dir}", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
