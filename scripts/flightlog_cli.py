"""flightlog: show what a flight log holds, convert a PX4 ULog to schema-v1 CSV.

    flightlog info LOG          vehicle, firmware, rates, modes, validity, what commands can do
    flightlog convert LOG.ulg --out FLIGHT.csv   (writes FLIGHT.csv and FLIGHT.csv.json)

LOG is a schema-v1 CSV or a PX4 ULog (chosen by content). ``info`` also describes a readable
ULog that no command can use, and says why. Exit codes: 0 done, 2 bad input.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from flightlog.atomic_output import OutputError, check_not_an_input, check_writable_file
from flightlog.flight_log_files import check_csv_log_name
from flightlog.info import describe_log, describe_unusable_ulog
from flightlog.reader import read_log
from flightlog.schema import FlightLogError, sidecar_path, write_flight_log
from flightlog.ulog import damage_note, is_ulog, summarise_ulog
from scripts.one_line_parser import OneLineParser, output_path

EXIT_BAD_INPUT = 2


@dataclass(frozen=True)
class FlightlogArgs:
    """Parsed command line: subcommand, the log, and the output path for convert."""

    command: str
    log: Path
    out: Path | None


def parse_args(argv: list[str] | None) -> FlightlogArgs:
    parser = OneLineParser(
        prog="flightlog",
        description="Inspect and convert flight logs.",
        epilog="Exit codes: 0 done, 2 bad input.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    info = sub.add_parser("info", help="what a log holds and what each command can do with it")
    info.add_argument("log", type=Path)
    conv = sub.add_parser("convert", help="PX4 ULog -> schema-v1 CSV + JSON sidecar")
    conv.add_argument("log", type=Path)
    conv.add_argument("--out", required=True, type=output_path, help="CSV path to write")
    args = parser.parse_args(argv)
    return FlightlogArgs(args.command, args.log, getattr(args, "out", None))


def convert(log_path: Path, out: Path) -> tuple[Path, str | None]:
    """Read any log and write it as schema-v1 CSV + sidecar, each atomically (temp, then
    rename); the CSV's path and, for a damaged ULog, its :func:`damage_note` (else None). The
    output place is checked before writing (OutputError in one line), so a folder or a file in
    the way leaves nothing behind, not even the sidecar."""
    log = read_log(log_path)
    check_not_an_input(out, [log_path])
    check_csv_log_name(out)
    check_writable_file(out)
    check_writable_file(sidecar_path(out))
    return write_flight_log(out, log), damage_note(log)


def _info_lines(path: Path) -> list[str]:
    """describe_log of the mapped log; for a ULog the mapping refuses (no velocity command,
    not a multirotor, no valid motion), what the raw ULog holds and the one-line reason."""
    try:
        return describe_log(read_log(path))
    except FlightLogError as exc:
        if not is_ulog(path):
            raise
        reason = str(exc).removeprefix(f"{path}: ")
        return [f"file: {path}", *describe_unusable_ulog(summarise_ulog(path), reason)]


def main(argv: list[str] | None = None) -> int:
    try:
        args = parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    try:
        if args.command == "info":
            print("\n".join(_info_lines(args.log)))
        else:
            assert args.out is not None
            out, damaged = convert(args.log, args.out)
            if damaged:
                print(f"flightlog: warning: {damaged}", file=sys.stderr)
            print(f"wrote {out} and {sidecar_path(out)}", file=sys.stderr)
    except OutputError as exc:
        print(f"flightlog: --out {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except FlightLogError as exc:
        print(f"flightlog: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 0


if __name__ == "__main__":
    sys.exit(main())
