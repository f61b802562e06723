"""[Ostafew16]'s path-repeating experiments on its own robots:
`python -m scripts.rover --regime rover_exp1 --out DIR`.

Regimes ([Ostafew16] section 5; the robots are vehicle_sim.rover's presets):
  rover_exp1  30 m path at a fixed 0.4 m/s, 20 trials, 50 kg skid-steer (Husky)
  rover_exp2  60 m loop, speed scheduler, 20 trials, 150 kg skid-steer (ROC6)
  rover_exp3  100 m loop, speed scheduler, 10 trials, 600 kg Ackermann (DMRV)
  example     section 3.4's illustrative example: feedback vs MPC vs LB-NMPC (Fig. 4)

Writes into --out: REGIME.png (max and RMS e_L [m] / e_H [rad] per trial, e_L along the path
in the first and the last trial, the scheduled speed along the path per trial, travel time per
trial) and REGIME.json (the per-trial numbers and
the reductions 1 - last / first trial); `example` writes fig4_illustrative.png and takes no
--trials or --seed. Each trial is said on stderr as it ends, then the files written; the
summary is printed on stdout (for `example`, each controller's RMS tracking error of z).
Ctrl-C stops a regime or the example with exit 130 and writes nothing.
A full regime takes about 25-60 s of CPU; --quick drives 2 trials (learning needs one before
it). `study --regime rover_exp1 ...` runs this command. Exit 2 with one line on bad input.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable

from flightlog.atomic_output import OutputError, check_writable_dir
from scripts.one_line_parser import OneLineParser, output_path

REGIMES = ("rover_exp1", "rover_exp2", "rover_exp3", "example")
QUICK_TRIALS = 2


def _seed(text: str) -> int:
    """A trial seed (argparse ``type``): NumPy's generators take integers >= 0 only. Both
    refusals are said here, since argparse names the function in its own ("invalid _seed
    value")."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {value}")
    return value


def main(argv: list[str] | None = None, prog: str = "rover") -> int:
    """Run a rover regime; returns the exit code. ``prog``: the command's name in its lines
    (``study`` when ``study --regime rover_exp1`` runs it)."""
    ap = OneLineParser(
        prog=prog, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--regime", required=True, help=f"one of {', '.join(REGIMES)}")
    ap.add_argument(
        "--out", type=output_path, default="out/rover", help="output folder (default out/rover)"
    )
    ap.add_argument("--trials", type=int, default=None, help="override the number of trials")
    ap.add_argument(
        "--quick", action="store_true", help=f"{QUICK_TRIALS} trials (unless --trials is given)"
    )
    ap.add_argument("--seed", type=_seed, default=0, help="draws of starts, localisation, terrain")
    try:
        args = ap.parse_args(argv)
    except SystemExit as exc:  # --help (0) or a one-line usage error (2): the exit code
        return int(exc.code or 0)
    if args.regime == "example" and (args.trials is not None or args.quick or args.seed != 0):
        print(f"{prog}: error: --regime example has no trials or draws; drop --trials, --quick "
              "and --seed", file=sys.stderr)  # fmt: skip
        return 2
    if args.quick and args.trials is None:
        args.trials = QUICK_TRIALS
    if args.regime not in REGIMES:
        known = ", ".join(REGIMES)
        print(f"{prog}: error: --regime {args.regime!r} is unknown; use one of {known}",
              file=sys.stderr)  # fmt: skip
        return 2
    if args.trials is not None and args.trials < 1:
        print(f"{prog}: error: --trials must be >= 1, got {args.trials}", file=sys.stderr)
        return 2
    try:  # before any trial: a folder that cannot be made is found now (made when written)
        check_writable_dir(args.out)
    except OutputError as exc:
        print(f"{prog}: error: --out {exc}", file=sys.stderr)
        return 2
    start = time.process_time()

    def progress(message: str) -> None:
        print(f"{prog} [{time.process_time() - start:6.1f} s CPU] {message}", file=sys.stderr)

    try:
        written, result = _run(args.regime, args.out, args.trials, args.seed, progress)
    except KeyboardInterrupt:  # the files are written at the end, each whole
        print(f"{prog}: interrupted; nothing written to {args.out}", file=sys.stderr)
        return 130
    except OutputError as exc:  # the folder checked above failed later (full, removed)
        print(f"{prog}: error: --out {exc}", file=sys.stderr)
        return 2
    print(f"{prog}: wrote {' and '.join(written)}", file=sys.stderr)
    print(json.dumps(result, indent=1))
    return 0


def _run(
    regime: str, out: str, trials: int | None, seed: int, progress: Callable[[str], None]
) -> tuple[list[str], dict]:
    """Run ``regime`` into the folder ``out``: (the files written, the summary printed)."""
    if regime == "example":
        progress("example: feedback, MPC and LB-NMPC on section 3.4's system")
        from experiments.rover.illustrative import write_figure

        written = [os.path.join(out, "fig4_illustrative.png")]
        return written, {"rms_tracking_error_z": write_figure(written[0])}
    from experiments.rover.report import run_regime

    result = run_regime(regime, out, trials, seed, progress)
    return [os.path.join(out, f"{regime}.{ext}") for ext in ("png", "json")], result


if __name__ == "__main__":
    sys.exit(main())
