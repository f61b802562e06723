"""`diagnose`: show what a simulation config gets wrong about measured flights, and fix it.

    diagnose LOGS... --sim-config FILE|PRESET --out DIR

LOGS are schema-v1 CSV flight logs (with their .json sidecars) or PX4 ULog files (.ulg).
Writes DIR/report.json (schema diagnosis/2), DIR/report.md with PNG plots, and
DIR/extended_config.toml (the config plus the accepted effects with fitted parameters).
Progress goes to stderr. Exit codes: 0 done, 2 bad input (one line saying why).
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from diagnosis.diagnosis import diagnose
from diagnosis.extend_config import write_extended_config
from diagnosis.forces import ForceDataError
from diagnosis.report import write_report
from flightlog.schema import FlightLogError, read_flight_log
from flightlog.ulog import read_ulog
from vehicle_sim import SimConfigError, load_sim_config

EXIT_OK = 0
EXIT_BAD_INPUT = 2
EXTENDED_CONFIG_NAME = "extended_config.toml"


@dataclass(frozen=True)
class DiagnoseArgs:
    """Parsed command line: log files, config path or preset name, output directory."""

    logs: tuple[Path, ...]
    sim_config: str
    out_dir: Path


def parse_args(argv: list[str] | None) -> DiagnoseArgs:
    parser = argparse.ArgumentParser(
        prog="diagnose",
        description="Compare a simulation config with measured flight logs, name what it gets "
        "wrong (effect vocabulary), fit it, write report and extended config.",
        epilog="Exit codes: 0 done, 2 bad input.",
    )
    parser.add_argument(
        "logs", nargs="+", type=Path, help="schema-v1 flight logs (CSV) or PX4 ULog files (.ulg)"
    )
    parser.add_argument(
        "--sim-config", required=True, help="simulation config TOML file or preset name"
    )
    parser.add_argument("--out", required=True, type=Path, help="output directory")
    args = parser.parse_args(argv)
    return DiagnoseArgs(tuple(args.logs), args.sim_config, args.out)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    start = time.monotonic()

    def progress(msg: str) -> None:
        print(f"[{time.monotonic() - start:6.1f} s] {msg}", file=sys.stderr, flush=True)

    try:
        sim_config = load_sim_config(args.sim_config)
        logs = [read_ulog(p) if p.suffix == ".ulg" else read_flight_log(p) for p in args.logs]
        progress(f"read {len(logs)} log(s), {sum(log.n_rows for log in logs)} rows")
        result = diagnose(logs, sim_config, progress=progress)
    except (SimConfigError, FlightLogError, ForceDataError) as exc:
        print(f"diagnose: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    args.out_dir.mkdir(parents=True, exist_ok=True)
    extended = write_extended_config(
        args.sim_config, result.added_effects, args.out_dir / EXTENDED_CONFIG_NAME
    )
    write_report(result, args.out_dir, [p.name for p in args.logs], args.sim_config, extended)
    verdict = ", ".join(result.verdict) or "none"
    progress(f"verdict: {verdict}; gain {result.gain:.1f}x; report in {args.out_dir}")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
