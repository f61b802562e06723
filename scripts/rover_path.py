"""`rover-path`: teach a rover a path by driving it once, then repeat it trial after trial.

    rover-path teach --out PATH.csv [--url udpin://0.0.0.0:14540] [--max-distance M]
                     [--drive 3:0,4.7:0.67 --drive-speed 0.5] [--spacing 0.25]
    rover-path teach --from-log DRIVE.ulg --out PATH.csv [--start-s S --end-s S]
    rover-path repeat --path PATH.csv [--experience EXP.npz] [--trials 3]
                      [--speed 0.5 | --scheduler experiment_2] [--drive-back [turn|reverse]]
                      [--tuning husky_50kg|roc6_150kg|dmrv_600kg] [--out DIR]

[Ostafew16]'s teach and repeat with learning, for a PX4 rover (or `vehicle-sim --vehicle
husky_50kg`) over MAVLink, as the companion reaches it (--link pymavlink or mavsdk, --url as
the companion's, or pymavlink's udpin:HOST:PORT), or in process (--link inprocess --vehicle).

teach: records the rover's position while someone drives it (a pilot in MANUAL, a mission),
from arming until it disarms, --max-distance is driven, --timeout passes or Ctrl-C; with
--drive the companion drives a pattern of LENGTH_M:CURVATURE_1PM segments itself in OFFBOARD
(curvature > 0 turns left). Writes the path (CSV ``x_m,y_m``: metres north and west of the
local origin, one row per vertex --spacing apart), atomically. With --from-log it takes the
drive from a PX4 ULog instead (its vehicle_local_position, over --start-s to --end-s seconds
from the log's start, else the stretch it was armed): stops are left out, a drive that turns
back on itself is refused naming its longest one-way stretch (experiments.rover.teach_from_log).

repeat: drives the path --trials times in OFFBOARD with the LB-NMPC (tuned as [Ostafew16]'s
experiment on the rover --tuning names; in process --vehicle's), learning from trial to
trial in experience bins kept in --experience (npz, written after each trial, read at the
start: the next run goes on learning where this one stopped). One line per trial on stdout;
repeat.json and repeat.png (errors and travel time per trial, speeds along the path) in --out
at the end. Each trial starts at the path's start: a loop ends there; after an open path
--drive-back drives back to it: `turn` (the default: turn in place, the straight line, turn; a
skid-steer rover, a clear line) or `reverse` (backwards along the path itself, on ground
already driven; any rover, Ackermann too). Without it an open path takes --trials 1. A rover
not at the start is refused in one line.

Exit codes: 0 done; 1 failed (no vehicle or position, link lost, refused, a teach pass too
short or not finite, a trial stopped or not at its end in time: the rover was sent a zero
velocity and Hold); 2 bad input (options, path, experience file or --from-log's log); 3
handed over (someone switched the rover out of OFFBOARD: nothing more was sent); 130 Ctrl-C,
143 SIGTERM (Hold, or nothing sent before the first trial arms the rover).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from companion.app import DEFAULT_URL
from companion.link import Link, LinkError
from companion.runner import Terminated
from flightlog.atomic_output import (
    OutputError,
    check_not_an_input,
    check_writable_dir,
    check_writable_file,
    write_figure_atomic,
    write_text_atomic,
)
from scripts.one_line_parser import OneLineParser, output_path
from scripts.stop_signals import stop_signals_answered

if TYPE_CHECKING:
    from planners.rover.path import TaughtPath

PROG = "rover-path"
LINKS = ("pymavlink", "mavsdk", "inprocess")
DRIVE_BACK_WAYS = ("turn", "reverse")  # experiments.rover.drive_back.DriveBack.WAYS
EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_HANDED_OVER = 0, 1, 2, 3
EXIT_INTERRUPTED, EXIT_TERMINATED = 130, 143
DEFAULT_SPEED_MPS = 0.5


class BadInput(ValueError):
    """A bad option or input file, found before anything drives; one line."""


def _positive(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text}")
    return value


def _non_negative(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text}")
    return value


def _pattern(text: str) -> list[tuple[float, float]]:
    """``L:C,L:C``: segments of length L > 0 [m] and curvature C [1/m] (> 0 turns left)."""
    segments = []
    for part in text.split(","):
        try:
            length, curvature = (float(v) for v in part.split(":"))
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{part!r} is not LENGTH_M:CURVATURE_1PM (e.g. 3:0,4.7:0.67)"
            ) from None
        if not (math.isfinite(length) and length > 0 and math.isfinite(curvature)):
            raise argparse.ArgumentTypeError(f"{part!r}: need a length > 0 and a finite curvature")
        segments.append((length, curvature))
    return segments


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    from experiments.rover.tuning import NMPC_TUNING

    parser = OneLineParser(
        prog=PROG,
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,  # (the doc ends with the exit codes)
    )
    sub = parser.add_subparsers(dest="command", required=True)
    # No abbreviations: repeat's --drive would be taken as --drive-back (teach's --drive given
    # to repeat said "--drive-back: invalid choice: '3:0'").
    teach = sub.add_parser(
        "teach", help="record the path the rover is driven along", allow_abbrev=False
    )
    repeat = sub.add_parser(
        "repeat", help="drive a taught path trial after trial, learning", allow_abbrev=False
    )
    for p in (teach, repeat):
        p.add_argument("--link", choices=LINKS, help="how to reach it (default pymavlink)")
        p.add_argument("--url", help=f"MAVLink URL (default {DEFAULT_URL})")
        p.add_argument("--vehicle", help="rover preset (--link inprocess; default husky_50kg)")
        p.add_argument("--seed", type=int, help="simulator seed (--link inprocess; default 0)")
        p.add_argument("--spacing", type=_positive, default=0.25, help="vertex spacing [m]")
    teach.add_argument("--out", required=True, type=output_path, help="path CSV to write")
    teach.add_argument("--max-distance", type=_positive, default=math.inf, help="stop after [m]")
    teach.add_argument(
        "--timeout",
        type=_positive,
        default=math.inf,
        help="stop recording this long [s] after the rover answered (it is waited for up to 30 s)",
    )
    teach.add_argument(
        "--drive", type=_pattern, default=None, metavar="L:C,...",
        help="drive this pattern in OFFBOARD (length [m]:curvature [1/m] per segment)",
    )  # fmt: skip
    teach.add_argument("--drive-speed", type=_positive, default=0.5, help="for --drive [m/s]")
    teach.add_argument(
        "--from-log", type=Path, default=None, metavar="DRIVE.ulg",
        help="take the drive from this PX4 ULog (its local position) instead of a live one",
    )  # fmt: skip
    for edge in ("start", "end"):
        teach.add_argument(
            f"--{edge}-s", type=_non_negative, default=None,
            help=f"--from-log: the span's {edge} [s from the log's start] (default: the stretch "
            "it was armed, or the whole log when arming is not logged)",
        )  # fmt: skip
    repeat.add_argument("--path", required=True, type=Path, help="path CSV from teach")
    repeat.add_argument(
        "--experience", type=output_path, default=None,
        help="experience file (npz) to continue from and to update (default: beside --path, "
        "PATH.experience.npz)",
    )  # fmt: skip
    repeat.add_argument(
        "--trials", type=int, default=3,
        help="trials in this run (default %(default)s; an open path needs --drive-back for more "
        "than 1)",
    )  # fmt: skip
    speeds = repeat.add_mutually_exclusive_group()
    speeds.add_argument(
        "--speed", type=_positive, default=None,
        help=f"fixed speed [m/s] (default {DEFAULT_SPEED_MPS:g})",
    )  # fmt: skip
    speeds.add_argument(
        "--scheduler", default=None, help="speed scheduler: experiment_2 or experiment_3 "
        "([Ostafew16] Table I); the schedule is kept in the experience file",
    )  # fmt: skip
    repeat.add_argument(
        "--drive-back", nargs="?", const="turn", choices=DRIVE_BACK_WAYS, default=None,
        help="after an open path, drive back to its start: turn (the default: turn in place, "
        "the straight line, turn; skid steer) or reverse (backwards along the path; any rover)",
    )  # fmt: skip
    repeat.add_argument(
        "--tuning", choices=sorted(NMPC_TUNING), default=None,
        help="the NMPC weights of the paper's experiment on this rover (default: --vehicle's "
        "in process; over MAVLink the planner's defaults, which do not suit an Ackermann rover)",
    )  # fmt: skip
    repeat.add_argument(
        "--out", type=output_path, default=Path("out/rover_path"),
        help="folder for repeat.json and repeat.png (default %(default)s)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if args.command == "teach":
        _check_from_log_options(parser, args)
    args.link = args.link or "pymavlink"
    if args.link == "inprocess" and args.url is not None:
        parser.error("--url is for a MAVLink link; --link inprocess drives a rover simulated here")
    args.url = args.url or DEFAULT_URL
    if args.command == "repeat" and args.trials < 1:
        parser.error(f"argument --trials: must be >= 1, got {args.trials}")
    for option, given in (("--vehicle", args.vehicle), ("--seed", args.seed)):
        if args.link != "inprocess" and given is not None:
            parser.error(
                f"{option} is for --link inprocess; over {args.link} the rover is whatever "
                f"answers at --url (start `vehicle-sim --vehicle PRESET` for a simulated one)"
            )
    args.vehicle = args.vehicle or "husky_50kg"
    if args.command == "repeat" and args.tuning is None and args.link == "inprocess":
        args.tuning = args.vehicle
    args.seed = 0 if args.seed is None else args.seed
    return args


def _check_from_log_options(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """--start-s/--end-s need --from-log; --from-log takes no live-teach option (nor a link:
    nothing is reached)."""
    if args.from_log is None:
        for option, given in (("--start-s", args.start_s), ("--end-s", args.end_s)):
            if given is not None:
                parser.error(f"{option} cuts a span of --from-log DRIVE.ulg; pass --from-log")
        return
    live = (("--drive", args.drive), ("--max-distance", math.isfinite(args.max_distance) or None),
            ("--timeout", math.isfinite(args.timeout) or None), ("--link", args.link),
            ("--url", args.url), ("--vehicle", args.vehicle), ("--seed", args.seed))  # fmt: skip
    for option, given in live:
        if given is not None:
            parser.error(
                f"{option} is for a live teach; --from-log takes the drive from the log "
                "(cut it with --start-s/--end-s)"
            )


def _say(message: str) -> None:
    print(f"{PROG}: {message}", file=sys.stderr, flush=True)


def open_link(args: argparse.Namespace) -> Link:
    """The Link the options ask for, not yet connected (BadInput on a bad URL or preset)."""
    if args.link == "inprocess":
        from companion.inprocess_rover_link import InProcessRoverLink

        try:
            return InProcessRoverLink.from_preset(args.vehicle, args.seed)
        except ValueError as exc:
            raise BadInput(f"--vehicle: {exc}") from None
    url = args.url
    if "://" not in url and url.startswith(("udpin:", "udpout:")):  # pymavlink's spelling
        url = url.replace(":", "://", 1)
    from companion.pymavlink_link import pymavlink_device

    try:
        pymavlink_device(url)
    except ValueError as exc:
        raise BadInput(f"--url: {exc}") from None
    if args.link == "mavsdk":
        from companion.mavsdk_link import MavsdkLink

        return MavsdkLink(url)
    from companion.pymavlink_link import PymavlinkLink

    return PymavlinkLink(url)


def teach(args: argparse.Namespace) -> int:
    from experiments.rover.link_commands import NotARover
    from experiments.rover.teach import HandedOver, TeachError, record_teach, turns_not_driven
    from planners.rover.path_file import path_csv_text

    if args.from_log is not None:
        return teach_from_log(args)
    if args.link == "inprocess" and args.drive is None:
        raise BadInput("--link inprocess: nobody drives a simulated rover in process; pass --drive")
    try:
        check_writable_file(args.out)
    except OutputError as exc:
        raise BadInput(f"--out {exc}") from None
    link = open_link(args)
    try:
        _say(f"teaching over {args.link}; the path goes to {args.out}")
        taught = record_teach(
            link, args.spacing, args.max_distance, args.timeout, args.drive, args.drive_speed,
            progress=_say,
        )  # fmt: skip
    except HandedOver as exc:
        _say(str(exc))
        return EXIT_HANDED_OVER
    except NotARover as exc:
        _say(f"error: {exc}")
        return EXIT_BAD_INPUT
    except (TeachError, LinkError) as exc:
        _say(f"error: {exc}")
        return EXIT_FAILED
    finally:
        link.close()
    path = taught.path
    try:
        write_text_atomic(args.out, path_csv_text(path))
    except OutputError as exc:
        raise BadInput(f"--out {exc}") from None
    _say(f"{_wrote(args.out, path)}; recording ended: {taught.ended_for}")
    for line in turns_not_driven(args.drive or (), path):
        _say(f"warning: {line}")
    return EXIT_OK


def _wrote(out: Path, path: TaughtPath) -> str:
    """What a teach says it wrote: vertices, spacing, length, loop or open."""
    from experiments.rover.path_start import end_gap_m, is_loop

    gap = end_gap_m(path)
    shape = "a loop" if is_loop(path) else f"open: its end is {gap:.1f} m from its start"
    return (
        f"wrote {out}: {len(path)} vertices {path.spacing_m:.2f} m apart, {path.length_m:.1f} m "
        f"({shape})"
    )


def teach_from_log(args: argparse.Namespace) -> int:
    """``teach --from-log``: the path of a recorded drive; a log it cannot use is bad input."""
    from experiments.rover.teach import TeachError
    from experiments.rover.teach_from_log import teach_from_track
    from flightlog.schema import FlightLogError
    from flightlog.ulog_track import read_ulog_track
    from planners.rover.path_file import path_csv_text

    try:
        check_writable_file(args.out)
        check_not_an_input(args.out, [args.from_log])
    except OutputError as exc:
        raise BadInput(f"--out {exc}") from None
    try:
        track = read_ulog_track(args.from_log)
    except FlightLogError as exc:
        raise BadInput(f"--from-log {exc}") from None
    if track.damage:
        _say(f"warning: {track.damage}")
    try:
        taught = teach_from_track(track, args.spacing, args.start_s, args.end_s)
    except TeachError as exc:
        raise BadInput(f"{exc}; nothing written") from None
    path = taught.path
    try:
        write_text_atomic(args.out, path_csv_text(path))
    except OutputError as exc:
        raise BadInput(f"--out {exc}") from None
    for note in taught.notes:
        _say(note)
    (a, b), origin = taught.span_s, track.origin_deg
    vehicle = f", {track.vehicle}" if track.vehicle else ""
    where = f"; local origin {origin[0]:.6f}, {origin[1]:.6f} deg" if origin else ""
    _say(
        f"{_wrote(args.out, path)}; from {track.name} {a:.1f}-{b:.1f} s "
        f"({taught.span_from}{vehicle}){where}"
    )
    return EXIT_OK


def _repeat_inputs(args: argparse.Namespace):  # noqa: ANN202 (a tuple of what repeat needs)
    from experiments.rover import learner
    from experiments.rover.experience_file import ExperienceFileError, load_experience
    from experiments.rover.path_start import end_gap_m, is_loop
    from planners.rover.path_file import PathFileError, read_path_file
    from planners.rover.speed_scheduler import TABLE_I, initial_schedule

    try:
        path = read_path_file(args.path, args.spacing)
    except PathFileError as exc:
        raise BadInput(f"--path {exc}") from None
    experience = args.experience or args.path.with_suffix(".experience.npz")
    out_dir = args.out
    try:
        check_writable_file(experience)
        check_not_an_input(experience, [args.path])
    except OutputError as exc:
        raise BadInput(f"--experience {exc}") from None
    try:
        check_writable_dir(out_dir)
    except OutputError as exc:
        raise BadInput(f"--out {exc}") from None
    scheduler = None
    if args.scheduler is not None:
        if args.scheduler not in TABLE_I:
            raise BadInput(f"--scheduler {args.scheduler!r} is unknown; use one of "
                           f"{', '.join(TABLE_I)}")  # fmt: skip
        scheduler = TABLE_I[args.scheduler]
    if args.trials > 1 and not is_loop(path) and not args.drive_back:
        raise BadInput(
            f"--path {args.path} is open (its end is {end_gap_m(path):.1f} m from its start): "
            "after trial 1 the rover is not at its start; pass --drive-back (turn or "
            "reverse) to drive back between trials, teach a loop, or run --trials 1"
        )
    gp = learner.make_history_gp()
    try:
        memory = load_experience(experience, gp, path)
    except ExperienceFileError as exc:
        raise BadInput(f"--experience {exc}") from None
    if scheduler is None:
        schedule = np.full(len(path), args.speed or DEFAULT_SPEED_MPS)
    elif memory.schedule_mps is not None:
        schedule = np.clip(memory.schedule_mps, scheduler.v_min_mps, scheduler.v_max_mps)
    else:
        schedule = initial_schedule(len(path), scheduler)
    return path, experience, scheduler, gp, memory, schedule


def repeat(args: argparse.Namespace) -> int:
    from experiments.rover.drive_back import DriveBack
    from experiments.rover.experience_file import save_experience
    from experiments.rover.link_commands import NotARover, require_a_rover
    from experiments.rover.repeat import RepeatOutcome, Trial, repeat_path
    from experiments.rover.repeat_report import figure, history_row, summary, trial_line
    from experiments.rover.tuning import NMPC_TUNING, tuning_for

    path, experience, scheduler, gp, memory, schedule = _repeat_inputs(args)
    link = open_link(args)
    tuning = args.tuning if args.tuning in NMPC_TUNING else None
    rover_tuning = tuning_for(tuning or "")
    _say(
        f"{args.path}: {len(path)} vertices, {path.length_m:.1f} m; {experience}: "
        + (f"{len(gp)} experiences from {_trials(memory.trials_done)}" if memory.trials_done
           else "no experience yet")
        + (f"; NMPC tuned for {tuning}" if tuning
           else "; NMPC on the planner's defaults (an Ackermann rover wants --tuning)")
    )  # fmt: skip
    driven: list[Trial] = []
    history = [*memory.history]

    def trial_done(trial: Trial, next_schedule: np.ndarray) -> None:
        print(trial_line(trial), flush=True)
        driven.append(trial)
        history.append(history_row(trial))
        save_experience(experience, gp, path, trial.number, next_schedule, np.array(history))

    back = None
    if args.drive_back:
        back = DriveBack(args.drive_back, min(args.speed or DEFAULT_SPEED_MPS, DEFAULT_SPEED_MPS))
    outcome = RepeatOutcome("interrupted", "Ctrl-C before any vehicle answered; nothing sent")
    code = EXIT_INTERRUPTED

    def driving() -> None:  # Ctrl-C from here on is answered with Hold
        outcome.detail = "Ctrl-C; the rover was sent Hold"

    try:
        link.connect(timeout_s=30.0)
        outcome.detail = "Ctrl-C before the first trial drove; nothing was sent to the rover"
        require_a_rover(link)
        outcome = repeat_path(
            link, path, args.trials, gp, schedule, scheduler, memory.trials_done + 1, back,
            trial_done, _say, rover_tuning.nmpc, rover_tuning.feedforward, on_drive=driving,
        )  # fmt: skip
        code = {"completed": EXIT_OK, "handed_over": EXIT_HANDED_OVER}.get(
            outcome.status, EXIT_FAILED
        )
    except NotARover as exc:
        outcome = RepeatOutcome("refused", str(exc))
        code = EXIT_BAD_INPUT
    except LinkError as exc:
        outcome = RepeatOutcome("stopped", str(exc))
        code = EXIT_FAILED
    except OutputError as exc:
        outcome = RepeatOutcome("stopped", f"--experience {exc}; the rover was sent Hold")
        code = EXIT_FAILED
    except KeyboardInterrupt as exc:
        if isinstance(exc, Terminated):
            outcome = RepeatOutcome("terminated", outcome.detail.replace("Ctrl-C", "SIGTERM"))
            code = EXIT_TERMINATED
    finally:
        link.close()
    outcome.trials = driven
    about = {
        "path": str(args.path), "vertices": len(path), "path_length_m": path.length_m,
        "experience": str(experience), "trials_before": memory.trials_done,
        "trials_after": memory.trials_done + len(driven), "experiences_after": len(gp),
        "speed_mps": None if scheduler else float(schedule[0]), "scheduler": args.scheduler,
        "nmpc_tuning": tuning,
    }  # fmt: skip
    if outcome.trials:
        try:
            rows = np.array(history)
            text = json.dumps(summary(outcome, about, rows), indent=1)
            write_text_atomic(Path(args.out) / "repeat.json", text)
            title = f"{args.path.name}: [Ostafew16] teach and repeat, trials 1-{int(rows[-1, 0])}"
            fig = figure(rows, title, path.s_m, outcome.trials)
            write_figure_atomic(fig, Path(args.out) / "repeat.png", dpi=90)
            _say(f"wrote {Path(args.out) / 'repeat.json'} and {Path(args.out) / 'repeat.png'}")
        except OutputError as exc:
            _say(f"error: --out {exc}")
            code = code or EXIT_FAILED
    _say(f"{outcome.status}: {outcome.detail}" if outcome.detail else outcome.status)
    return code


def _trials(n: int) -> str:
    return f"{n} trial" if n == 1 else f"{n} trials"


def main(argv: list[str] | None = None) -> int:
    try:
        args = parse_args(argv)
    except SystemExit as exc:  # --help (0) or a one-line usage error (2)
        return int(exc.code or 0)
    try:
        with stop_signals_answered():
            return teach(args) if args.command == "teach" else repeat(args)
    except BadInput as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as exc:
        _say("interrupted")
        return EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
