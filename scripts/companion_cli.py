"""`companion`: fly a mission file over a Link and write a schema-v1 flight log.

    companion MISSION --link {mavsdk,pymavlink,inprocess} [--url udpin://127.0.0.1:14540]
              [--planner pd|nmpc|nmpc_clutter] [--gp-model MODEL.npz] [--rate-hz 50]
              [--log FLIGHT.csv] [--seed 0] [--vehicle iris]   (--seed, --vehicle: inprocess;
                                                                 --url: the MAVLink links)

Without ``--log`` each flight's log is a new file, out/flights/flight_<UTC date_time>.csv, as
PX4 never writes a log over an earlier one; ``--log PATH`` writes there, as every command's
output option does, and a log already there is kept as PATH-stem.1.csv (the first free number).

Progress goes to stderr. Exit codes: 0 mission completed (goal reached, landed, disarmed);
1 flight failed or goal not reached (the vehicle was brought to HOLD and LAND); 2 bad input
(mission file, option, or a mission beyond the vehicle's PX4 limits, found before take-off); 3
handed over: someone else (a pilot, a ground station) switched the
vehicle out of OFFBOARD, so the companion stopped streaming and commanded nothing; 130
interrupted by Ctrl-C, 143 terminated by SIGTERM (in both the vehicle was sent a zero velocity,
HOLD and LAND, and the companion waited for it to disarm).
"""

from __future__ import annotations

import sys
from pathlib import Path

from companion.app import (
    DEFAULT_URL,
    LINK_KINDS,
    CompanionConfig,
    CompanionInputError,
    run_companion,
)
from companion.planner_registry import PLANNER_NAMES
from companion.runner import COMPANION_RT_PRIORITY, FlightOutcome, RunnerConfig, Terminated
from scripts.one_line_parser import OneLineParser, output_path
from scripts.stop_signals import stop_signals_answered

EXIT_COMPLETED = 0
EXIT_FAILED = 1
EXIT_BAD_INPUT = 2
EXIT_HANDED_OVER = 3
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143  # 128 + SIGTERM, as shells report it


def parse_args(argv: list[str] | None) -> CompanionConfig:
    """Command line -> config; argparse exits with code 2 on bad options."""
    parser = OneLineParser(
        prog="companion",
        description="Fly a mission file over MAVLink (MAVSDK or pymavlink) or in process.",
        epilog="Exit codes: 0 completed, 1 failed or goal not reached, 2 bad input, "
        "3 handed over to a pilot (nothing commanded), 130 Ctrl-C and 143 SIGTERM (vehicle "
        "sent HOLD and LAND).",
    )
    parser.add_argument("mission", type=Path, help="mission file (TOML)")
    parser.add_argument(
        "--link", choices=LINK_KINDS, default="mavsdk", help="how to reach it (default mavsdk)"
    )
    parser.add_argument(
        "--url", help=f"MAVLink URL, mavsdk and pymavlink links (default {DEFAULT_URL})"
    )
    parser.add_argument(
        "--planner",
        choices=PLANNER_NAMES,
        default="pd",
        help="pd (default): [Kulathunga23]'s PD regulator; nmpc: the NMPC (--gp-model to "
        "augment it); nmpc_clutter: the NMPC round sensed obstacles",
    )
    parser.add_argument(
        "--gp-model",
        type=Path,
        default=None,
        help="residual model from fit-gp: fly the NMPC augmented with it (--planner nmpc or "
        "nmpc_clutter)",
    )
    parser.add_argument(
        "--rate-hz", type=float, default=50.0, help="control loop rate [Hz] (default %(default)g)"
    )
    parser.add_argument(
        "--log",
        type=output_path,
        default=None,
        help="flight log (schema-v1 CSV) to write; a log already there is kept as "
        "PATH-stem.1.csv (default: a new file out/flights/flight_<UTC date_time>.csv)",
    )
    parser.add_argument("--seed", type=int, help="simulator seed (inprocess; default 0)")
    parser.add_argument("--vehicle", help="simulator preset or config (inprocess; default iris)")
    parser.add_argument(
        "--verbose", action="store_true", help="show MAVSDK's own log lines (hidden by default)"
    )
    parser.add_argument(
        "--realtime-priority",
        type=int,
        default=COMPANION_RT_PRIORITY,
        metavar="N",
        help="SCHED_FIFO priority of the control loop over MAVLink, as companion computers run "
        f"it (default {COMPANION_RT_PRIORITY}; 0: normal priority; where the system does not "
        "permit it, the flight says so and runs at normal priority)",
    )
    args = parser.parse_args(argv)
    in_process = args.link == "inprocess"
    ignored = [
        option
        for option, value, used in (
            ("--vehicle", args.vehicle, in_process),
            ("--seed", args.seed, in_process),
            ("--url", args.url, not in_process),
        )
        if value is not None and not used
    ]
    if ignored and in_process:
        parser.error(f"{ignored[0]} is for the mavsdk and pymavlink links, not --link inprocess")
    if ignored:
        parser.error(
            f"{' and '.join(ignored)} {'choose' if len(ignored) > 1 else 'chooses'} the "
            f"in-process simulator; over --link {args.link} "
            "the vehicle is the one answering at --url (start it with vehicle-sim --vehicle ...)"
        )
    try:
        runner = RunnerConfig(rate_hz=args.rate_hz, realtime_priority=args.realtime_priority)
    except ValueError as exc:
        parser.error(str(exc))
    return CompanionConfig(
        mission_path=args.mission,
        link=args.link,
        url=args.url or DEFAULT_URL,
        planner=args.planner,
        gp_model=args.gp_model,
        log_path=args.log,
        seed=0 if args.seed is None else args.seed,
        vehicle=args.vehicle or "iris",
        runner=runner,
        verbose=args.verbose,
    )


def _progress(message: str) -> None:
    print(f"companion: {message}", file=sys.stderr, flush=True)


def _summary(outcome: FlightOutcome) -> str:
    """The flight's last line: how it ended, where it landed (when it came down from a
    followed reference), how closely it tracked the reference (when it followed one: the
    figure to compare flights with and without ``--gp-model``) and its deadline misses (when
    it flew a control step)."""
    parts = [
        outcome.detail
        if outcome.detail.startswith(outcome.status)  # "interrupted by Ctrl-C"
        else f"{outcome.status}: {outcome.detail}"
    ]
    if outcome.landed_error_m is not None:
        parts.append(f"landed {outcome.landed_error_m:.2f} m from the goal")
    if outcome.tracking_rmse_m is not None:
        parts.append(f"tracking RMSE {outcome.tracking_rmse_m:.3f} m")
    if outcome.ticks:
        parts.append(f"{outcome.deadline_misses} deadline misses in {outcome.ticks} steps")
    return "; ".join(parts)


def main(argv: list[str] | None = None) -> int:
    config = parse_args(argv)
    try:
        with stop_signals_answered():
            result = run_companion(config, _progress)
    except CompanionInputError as exc:
        print(f"companion: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as exc:
        _progress("interrupted again during the safe stop; the vehicle was commanded to land")
        return EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED
    outcome = result.outcome
    if outcome.status == "handed_over":
        print(f"companion: {outcome.detail}", file=sys.stderr, flush=True)
        return EXIT_HANDED_OVER
    if outcome.status == "refused":
        print(f"companion: error: {outcome.detail}", file=sys.stderr, flush=True)
        return EXIT_BAD_INPUT
    _progress(_summary(outcome))
    if outcome.status == "completed":
        return EXIT_COMPLETED
    if outcome.status == "interrupted":
        return EXIT_INTERRUPTED
    if outcome.status == "terminated":
        return EXIT_TERMINATED
    return EXIT_FAILED


if __name__ == "__main__":
    sys.exit(main())
