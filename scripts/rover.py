"""Paper 004 on its own robots: `python -m scripts.rover --regime rover_exp1 --out DIR`.

Regimes: rover_exp1 (30 m, 0.4 m/s, 20 trials, 50 kg skid-steer), rover_exp2 (60 m loop,
scheduler, 20 trials, 150 kg skid-steer), rover_exp3 (100 m loop, scheduler, 10 trials, 600 kg
Ackermann), example (section 3.4's illustrative example, Fig. 4). Exit 2 on bad input.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

from flightlog.atomic_output import OutputError, check_writable_dir, describe_os_error
from scripts.one_line_parser import OneLineParser, output_path

REGIMES = ("rover_exp1", "rover_exp2", "rover_exp3", "example")


def main(argv: list[str] | None = None) -> int:
    ap = OneLineParser(prog="rover", description=__doc__.splitlines()[0])
    ap.add_argument("--regime", required=True, help=f"one of {', '.join(REGIMES)}")
    ap.add_argument("--out", type=output_path, default="rover_out", help="output folder")
    ap.add_argument("--trials", type=int, default=None, help="override the number of trials")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if args.regime not in REGIMES:
        print(f"rover: error: --regime {args.regime!r} is unknown; use one of {', '.join(REGIMES)}",
              file=sys.stderr)  # fmt: skip
        return 2
    if args.trials is not None and args.trials < 1:
        print(f"rover: error: --trials must be >= 1, got {args.trials}", file=sys.stderr)
        return 2
    if args.seed < 0:
        print(f"rover: error: --seed must be >= 0, got {args.seed}", file=sys.stderr)
        return 2
    try:  # before any trial: a folder that cannot be made is found now
        check_writable_dir(args.out)
        os.makedirs(args.out, exist_ok=True)
    except OutputError as exc:
        print(f"rover: --out {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"rover: --out {describe_os_error(Path(args.out), exc)}", file=sys.stderr)
        return 2
    if args.regime == "example":
        from experiments.rover.illustrative import write_figure

        result = write_figure(os.path.join(args.out, "fig4_illustrative.png"))
    else:
        from experiments.rover.report import run_regime

        def progress(message: str) -> None:
            print(f"rover: {args.regime} {message}", file=sys.stderr, flush=True)

        result = run_regime(args.regime, args.out, args.trials, args.seed, progress)
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
