"""vehicle-sim config-from-log LOG --out my_vehicle.toml [--preset iris]

Builds a simulation config whose flight control uses the log's PX4 parameters and whose mass
agrees with its hover thrust; what the log cannot tell comes from the preset and is listed as
assumed (in the TOML's comments and on stderr). Exit codes: 0 done, 2 bad input.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from flightlog.atomic_output import (
    OutputError,
    check_not_an_input,
    check_writable_file,
    write_text_atomic,
)
from flightlog.schema import FlightLogError
from scripts.one_line_parser import OneLineParser, output_path
from vehicle_sim.config import PRESET_NAMES
from vehicle_sim.config_from_log import config_from_log_file
from vehicle_sim.effects.base import SimConfigError


@dataclass(frozen=True)
class ConfigFromLogArgs:
    """Parsed command line: the log, the TOML to write, the preset for what is assumed."""

    log: Path
    out: Path
    preset: str


def parse_args(argv: list[str] | None) -> ConfigFromLogArgs:
    parser = OneLineParser(prog="vehicle-sim config-from-log", description=__doc__.split("\n\n")[1])
    parser.add_argument("log", type=Path, help="PX4 ULog (or schema-v1 CSV with px4_params)")
    parser.add_argument("--out", required=True, type=output_path, help="config TOML to write")
    parser.add_argument("--preset", default="iris", choices=PRESET_NAMES)
    args = parser.parse_args(argv)
    return ConfigFromLogArgs(args.log, args.out, args.preset)


def main(argv: list[str] | None = None) -> int:
    try:
        args = parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    try:
        built = config_from_log_file(args.log, args.preset)
        check_not_an_input(args.out, [args.log])
        check_writable_file(args.out)
        write_text_atomic(args.out, built.toml)
    except OutputError as exc:
        print(f"vehicle-sim config-from-log: --out {exc}", file=sys.stderr)
        return 2
    except (FlightLogError, SimConfigError, ValueError) as exc:
        print(f"vehicle-sim config-from-log: {exc}", file=sys.stderr)
        return 2
    for line in built.from_log:
        print(f"from the log: {line}", file=sys.stderr)
    for line in built.assumed:
        print(f"assumed: {line}", file=sys.stderr)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
