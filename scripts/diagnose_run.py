"""What `diagnose` (scripts.diagnose) does once its command line is read: one diagnosis of all
logs, or one per log with ``--batch``; the report sets written atomically."""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path

from diagnosis.diagnosis import diagnose
from diagnosis.extend_config import write_extended_config
from diagnosis.forces import ForceDataError
from diagnosis.report import headline, write_report
from experiments.batch_diagnose import DiagnosisJob, diagnose_each
from experiments.executors import SchedulerError, job_executor
from flightlog.atomic_output import OutputError, atomic_output_dir, check_writable_dir
from flightlog.reader import read_log, require_distinct, require_rates
from flightlog.schema import FlightLog, FlightLogError
from scripts.diagnose import EXIT_BAD_INPUT, EXIT_OK, DiagnoseArgs
from vehicle_sim import SimConfig, SimConfigError, load_sim_config

EXTENDED_CONFIG_NAME = "extended_config.toml"
BATCH_SUMMARY_NAME = "batch.json"

Progress = Callable[[str], None]


def run_diagnose(args: DiagnoseArgs) -> int:
    """Diagnose (one report set, or one per log with --batch); returns the exit code."""
    start = time.monotonic()

    def progress(msg: str) -> None:
        print(f"diagnose [{time.monotonic() - start:6.1f} s] {msg}", file=sys.stderr, flush=True)

    try:
        check_writable_dir(args.out_dir)  # before minutes of work, not after
        sim_config = load_sim_config(args.sim_config)
        if args.batch:
            return _run_batch(args, sim_config, progress)
        require_distinct(args.logs)  # one diagnosis of all logs: a flight twice counts twice
        logs = [_read_for_diagnosis(p) for p in args.logs]
        progress(f"read {len(logs)} log(s), {sum(log.n_rows for log in logs)} rows")
        for log in logs:
            if log.metadata.get("source") == "companion" and not log.has("thrust_n"):
                print(
                    f"diagnose: warning: {log.where} is the companion's log: MAVLink carries no "
                    "thrust or acceleration, so no force-residual cause (drags, wind, payload) "
                    "can be examined; diagnose the vehicle's onboard log: its PX4 .ulg, or "
                    "vehicle-sim --log",
                    file=sys.stderr,
                )
        result = diagnose(logs, sim_config, progress=progress)
        for warning in result.warnings:  # also in the report's headline
            print(f"diagnose: warning: {warning}", file=sys.stderr)
    except (SimConfigError, FlightLogError, ForceDataError, SchedulerError) as exc:
        print(f"diagnose: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OutputError as exc:
        print(f"diagnose: --out {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        with atomic_output_dir(args.out_dir) as tmp:  # the report set appears whole, or not
            extended = write_extended_config(
                args.sim_config, result.added_effects, tmp / EXTENDED_CONFIG_NAME
            )
            names = [p.name for p in args.logs]
            write_report(result, tmp, names, args.sim_config, args.out_dir / extended.name)
    except OutputError as exc:
        print(f"diagnose: --out {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    progress(f"verdict: {headline(result)}; report in {args.out_dir}")
    return EXIT_OK


def _read_for_diagnosis(path: Path) -> FlightLog:
    log = read_log(path)
    require_rates(log, "diagnose")
    return log


def _run_batch(args: DiagnoseArgs, sim_config: SimConfig, progress: Progress) -> int:
    """Diagnose each log on its own on the chosen executor, skipping (one line each) the logs
    that cannot be diagnosed; write the report sets and batch.json atomically."""
    missing = [str(p) for p in args.logs if not p.exists()]
    if missing:  # a typo, not a log to skip: nothing is diagnosed until the list is right
        print(
            f"diagnose: error: no such log: {', '.join(missing)}; check the path", file=sys.stderr
        )
        return EXIT_BAD_INPUT
    names = _unique_names(args.logs)
    path_of = dict(zip(names, args.logs, strict=True))
    skipped: dict[str, str] = {}  # name -> why
    jobs = []
    for name, path in path_of.items():
        try:
            jobs.append(DiagnosisJob(name, _read_for_diagnosis(path), sim_config))
        except FlightLogError as exc:
            skipped[name] = _reason(path, exc)
            print(f"diagnose: skipping {path}: {skipped[name]}", file=sys.stderr)
    where = args.scheduler or f"{args.workers} local processes"
    progress(f"batch: {len(jobs)} diagnoses on {where}")
    outcomes = []
    if jobs:
        with job_executor(args.workers, args.scheduler) as pool:
            outcomes = diagnose_each(jobs, pool, progress)
    results = {o.name: o.diagnosis for o in outcomes if o.diagnosis is not None}
    for name, result in results.items():  # as a single diagnosis says them (and batch.json)
        for warning in result.warnings:
            print(f"diagnose: warning: {path_of[name]}: {warning}", file=sys.stderr)
    for outcome in outcomes:
        if outcome.diagnosis is None:
            path = path_of[outcome.name]
            skipped[outcome.name] = _reason(path, outcome.skipped)
            print(f"diagnose: skipping {path}: {skipped[outcome.name]}", file=sys.stderr)
    if not results:
        print(
            f"diagnose: none of the {len(names)} logs can be diagnosed (each skipped above "
            "with its reason)",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    summary = []
    try:
        with atomic_output_dir(args.out_dir) as tmp:
            for name, path in path_of.items():
                if name in skipped:  # as given, and why
                    summary.append({"log": str(path), "skipped": skipped[name]})
                    continue
                result = results[name]
                (tmp / name).mkdir()
                extended = write_extended_config(
                    args.sim_config, result.added_effects, tmp / name / EXTENDED_CONFIG_NAME
                )
                final = args.out_dir / name / extended.name
                write_report(result, tmp / name, [path.name], args.sim_config, final)
                summary.append(
                    {
                        "log": str(path),  # as given: two logs may share a file name
                        "report": f"{name}/report.json",
                        "verdict": list(result.verdict),
                        "gain": result.gain if math.isfinite(result.gain) else None,
                        "warnings": list(result.warnings),
                    }
                )
            doc = {"schema": "diagnosis-batch/1", "sim_config": args.sim_config, "logs": summary}
            (tmp / BATCH_SUMMARY_NAME).write_text(json.dumps(doc, indent=2) + "\n")
    except OutputError as exc:
        print(f"diagnose: --out {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    left_out = f"; {len(skipped)} log(s) skipped ({BATCH_SUMMARY_NAME} says why)" if skipped else ""
    progress(f"batch: {len(results)} report sets in {args.out_dir}{left_out}")
    return EXIT_OK


def _reason(path: Path, error: object) -> str:
    """Why a log is skipped, without the path the error starts with (the line names it)."""
    return str(error).removeprefix(f"{path}: ")


def _unique_names(paths: tuple[Path, ...]) -> list[str]:
    """A folder name per log: its stem, numbered when two logs share one."""
    stems = [p.stem for p in paths]
    return [s if stems.count(s) == 1 else f"{i:03d}_{s}" for i, s in enumerate(stems)]
