"""Diagnose the built-in F450 preset against JSBSim's F450, the plant we did not write.

    python -m experiments.jsbsim_diagnosis --out DIR [--mission FILE ...] [--max-s S]

Flies the excitation missions in-process on the "jsbsim" backend (our flight control driving
JSBSim's F450) into DIR/logs, runs the diagnosis of the preset that claims to be the same
vehicle (default "f450": mass, inertia and geometry matched, effects off) into DIR/diagnosis,
and prints a Markdown summary: the ranked causes with fitted parameters and the gain (held-out
replay and closed-loop velocity RMSE, baseline vs extended config). Exit codes: 0 done,
2 bad input.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from diagnosis.excitation import ExcitationError, ExcitationSchedule, load_schedule
from diagnosis.fly_schedule import fly_schedule
from flightlog.atomic_output import OutputError, check_writable_dir
from flightlog.schema import write_flight_log
from scripts import diagnose
from scripts.one_line_parser import OneLineParser, output_path
from vehicle_sim import SimConfigError, load_sim_config

PROG = "jsbsim-diagnosis"
MISSION_DIR = Path(__file__).resolve().parents[1] / "missions"
DEFAULT_MISSIONS = ("excite_full.toml", "excite_speed.toml")
EXIT_OK = 0
EXIT_BAD_INPUT = 2


@dataclass(frozen=True)
class JsbsimDiagnosisConfig:
    """What to fly and diagnose.

    Attributes:
        out_dir: receives ``logs/`` (one schema-v1 log per mission) and ``diagnosis/``.
        missions: excitation mission files, flown one after the other.
        preset: the config (preset name or TOML path) the diagnosis judges.
        max_s: keep only the leading segments of each mission that fit in this OFFBOARD time
            [s] (None: whole missions).
        seed: simulator seed.
        rate_hz: setpoint and log rate [Hz].
    """

    out_dir: Path
    missions: tuple[Path, ...] = tuple(MISSION_DIR / m for m in DEFAULT_MISSIONS)
    preset: str = "f450"
    max_s: float | None = None
    seed: int = 0
    rate_hz: float = 20.0


def parse_args(argv: Sequence[str] | None) -> JsbsimDiagnosisConfig:
    parser = OneLineParser(prog=PROG, description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, type=output_path, help="output directory")
    parser.add_argument(
        "--mission",
        action="append",
        type=Path,
        metavar="FILE",
        help=f"excitation mission (repeatable; default: {', '.join(DEFAULT_MISSIONS)})",
    )
    parser.add_argument("--preset", default="f450", help="config judged (preset or TOML path)")
    parser.add_argument("--max-s", type=float, help="truncate each mission to about this time")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    if args.max_s is not None and not 0.0 < args.max_s < math.inf:
        parser.error(f"--max-s must be a finite time > 0 s, got {args.max_s}")
    defaults = JsbsimDiagnosisConfig(out_dir=args.out)
    return replace(
        defaults,
        missions=tuple(args.mission) if args.mission else defaults.missions,
        preset=args.preset,
        max_s=args.max_s,
        seed=args.seed,
    )


def truncated(schedule: ExcitationSchedule, max_s: float | None) -> ExcitationSchedule:
    """``schedule`` cut to its leading segments within ``max_s`` [s] (at least one segment)."""
    if max_s is None:
        return schedule
    kept, total_s = [], 0.0
    for seg in schedule.segments:
        if kept and total_s + seg.duration_s > max_s:
            break
        kept.append(seg)
        total_s += seg.duration_s
    return replace(schedule, segments=tuple(kept))


def fly_missions(config: JsbsimDiagnosisConfig) -> list[Path]:
    """Fly every mission on the "jsbsim" backend; returns the written log paths."""
    plant = replace(load_sim_config(config.preset), backend="jsbsim")
    schedules = [truncated(load_schedule(m), config.max_s) for m in config.missions]
    log_dir = config.out_dir / "logs"
    log_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for schedule in schedules:
        print(
            f"{PROG}: flying {schedule.name} ({schedule.duration_s:.0f} s) on jsbsim",
            file=sys.stderr,
            flush=True,
        )
        log = fly_schedule(plant, schedule, seed=config.seed, rate_hz=config.rate_hz)
        paths.append(write_flight_log(log_dir / f"{schedule.name}.csv", log))
    return paths


def summary_table(report: Mapping[str, Any]) -> str:
    """The Markdown summary of a ``diagnosis/1`` report (with its ``closed_loop`` key)."""
    lines = [
        "| cause | accepted | fitted parameters | explained | confidence |",
        "|---|---|---|---|---|",
    ]
    for cause in report["causes"]:
        params = "; ".join(f"{k} = {_fmt(v)}" for k, v in cause["params"].items()) or "-"
        accepted = "yes" if cause["name"] in report["verdict"] else "no"
        shares = f"{cause['explained_fraction']:.2f} | {cause['confidence']:.2f}"
        lines.append(f"| {cause['name']} | {accepted} | {params} | {shares} |")
    base, ext = report["baseline"], report["extended"]
    loop = report["closed_loop"]
    lines += [
        "",
        "| held-out velocity RMSE [m/s] | baseline | extended | gain |",
        "|---|---|---|---|",
        f"| replay | {base['replay_vel_rmse_mps']:.4f} | {ext['replay_vel_rmse_mps']:.4f} | "
        f"{ext['gain']:.2f} |",
        f"| closed loop | {loop['baseline_vel_rmse_mps']:.4f} | "
        f"{loop['extended_vel_rmse_mps']:.4f} | {loop['gain']:.2f} |",
        "",
        f"verdict: {', '.join(report['verdict']) or 'none'}",
    ]
    return "\n".join(lines)


def _fmt(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    return f"{value:.4g}" if isinstance(value, float) and math.isfinite(value) else str(value)


def main(argv: Sequence[str] | None = None) -> int:
    config = parse_args(argv)
    try:
        check_writable_dir(config.out_dir)  # before minutes of flying, not after
    except OutputError as exc:
        print(f"{PROG}: error: --out {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        logs = fly_missions(config)
    except (ExcitationError, SimConfigError) as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    out = config.out_dir / "diagnosis"
    argv_diagnose = [*map(str, logs), "--sim-config", config.preset, "--out", str(out)]
    code = diagnose.main(argv_diagnose)
    if code != EXIT_OK:
        return code
    print(summary_table(json.loads((out / "report.json").read_text())), flush=True)
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
