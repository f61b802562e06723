"""`bench`: measure the project's speed and accuracy figures and print them as a table.

Each part lives in ``experiments/bench/<part>.py`` and exposes ``run(progress, quick) -> dict``
of named figures (names are stable so they can be followed over time; see BENCHMARKS.md).
Timings are only compared against baselines measured in the same run: machines are noisy.

Usage:
    bench                      # every part, Markdown table on stdout
    bench --only gp --json     # one part, one JSON object
    bench --quick              # small sizes, for a smoke run

Ctrl-C stops it with exit 130 and prints the figures of the parts that ended before it.
"""

from __future__ import annotations

import importlib
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from scripts.one_line_parser import OneLineParser

EXIT_INTERRUPTED = 130

PARTS: dict[str, str] = {
    "sim": "experiments.bench.sim",
    "jsbsim": "experiments.bench.jsbsim",
    "gp": "experiments.bench.gp",
    "nmpc": "experiments.bench.nmpc",
    "link": "experiments.bench.link",
    "loop": "experiments.bench.loop",
    "diagnose": "experiments.bench.diagnose",
    "rover": "experiments.bench.rover",
    "clutter": "experiments.bench.clutter",
}


@dataclass(frozen=True)
class BenchConfig:
    """What to run: ``parts`` in order, ``quick`` for small sizes, ``as_json`` for the output."""

    parts: tuple[str, ...]
    quick: bool = False
    as_json: bool = False


def parse_args(argv: Sequence[str] | None) -> BenchConfig:
    parser = OneLineParser(
        prog="bench",
        description=__doc__.splitlines()[0],
        epilog="Exit codes: 0 done, 2 bad input, 130 stopped by Ctrl-C (the figures of the "
        "parts done are printed).",
    )
    parser.add_argument(
        "--only",
        action="append",
        metavar="PART",
        help=f"run only this part (repeatable): {', '.join(PARTS)}",
    )
    parser.add_argument("--quick", action="store_true", help="small sizes, for a smoke run")
    parser.add_argument("--json", action="store_true", help="print one JSON object of figures")
    args = parser.parse_args(argv)
    parts = tuple(args.only) if args.only else tuple(PARTS)
    unknown = [p for p in parts if p not in PARTS]
    if unknown:
        parser.error(f"unknown part {unknown[0]!r}; choose from {', '.join(PARTS)}")
    return BenchConfig(parts=parts, quick=args.quick, as_json=args.json)


def run_parts(
    config: BenchConfig, progress: Callable[[str], None], figures: dict[str, float]
) -> None:
    """Run the configured parts in order, merging their figures into ``figures`` as each part
    ends (so that the parts done are kept when a later one is stopped)."""
    for part in config.parts:
        module = importlib.import_module(PARTS[part])
        progress(f"[bench] {part} ...")
        start = time.perf_counter()
        figures.update(module.run(progress=progress, quick=config.quick))
        progress(f"[bench] {part} done in {time.perf_counter() - start:.1f} s")


def format_table(figures: dict[str, float]) -> str:
    """Figures as a two-column Markdown table."""
    lines = ["| figure | value |", "|---|---|"]
    lines += [f"| `{name}` | {value:.4g} |" for name, value in figures.items()]
    return "\n".join(lines)


def format_json(figures: dict[str, float]) -> str:
    """Figures as one JSON object; a figure a part could not measure (NaN, e.g. acados not
    installed) is null, since NaN is not JSON."""
    finite = {k: (v if math.isfinite(v) else None) for k, v in figures.items()}
    return json.dumps(finite, sort_keys=True, allow_nan=False)


def main(argv: Sequence[str] | None = None) -> int:
    config = parse_args(argv)

    def progress(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    figures: dict[str, float] = {}
    try:
        run_parts(config, progress, figures)
    except KeyboardInterrupt:
        done = "; the figures of the parts done are printed" if figures else ""
        print(f"bench: stopped by Ctrl-C{done}", file=sys.stderr)
        if figures:
            print(format_json(figures) if config.as_json else format_table(figures))
        return EXIT_INTERRUPTED
    print(format_json(figures) if config.as_json else format_table(figures))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
