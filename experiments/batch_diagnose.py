"""A batch diagnosis: every log diagnosed on its own, the jobs spread over an Executor.

Where ``diagnose LOGS...`` explains all logs together, ``diagnose --batch LOGS...`` asks the
question per log (e.g. one per airframe or per day of a fleet's flights) and writes one report
set per log plus a summary. Each job is a pure function of (log, config): the client reads the
files and ships the data, so a remote worker needs no access to them (see
:mod:`experiments.executors` for local processes vs a Dask cluster). A log whose data cannot
be diagnosed (e.g. never airborne) is skipped with its one-line reason, not the whole batch:
a folder of flights copied off an SD card holds some of those.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass

from diagnosis.diagnosis import Diagnosis, diagnose
from diagnosis.forces import ForceDataError
from diagnosis.report import headline
from flightlog.schema import FlightLog, FlightLogError
from vehicle_sim import SimConfig


@dataclass(frozen=True, eq=False)
class DiagnosisJob:
    """One log to diagnose against a simulation config (plain data: picklable)."""

    name: str
    log: FlightLog
    sim_config: SimConfig


@dataclass(frozen=True)
class JobOutcome:
    """One job's result: its diagnosis, or why its log could not be diagnosed (one line)."""

    name: str
    diagnosis: Diagnosis | None
    skipped: str | None = None


def run_diagnosis_job(job: DiagnosisJob) -> JobOutcome:
    """Diagnose one log in this process (the work unit); a log the diagnosis cannot use is
    returned as skipped with the reason, any other error propagates."""
    try:
        return JobOutcome(job.name, diagnose([job.log], job.sim_config))
    except (FlightLogError, ForceDataError) as exc:
        return JobOutcome(job.name, None, str(exc))


def diagnose_each(
    jobs: Sequence[DiagnosisJob], pool: Executor, progress: Callable[[str], None]
) -> list[JobOutcome]:
    """Diagnose every job on ``pool``; outcomes in the jobs' order."""
    outcomes = []
    for n, (job, outcome) in enumerate(
        zip(jobs, pool.map(run_diagnosis_job, jobs), strict=True), start=1
    ):
        if outcome.diagnosis is None:
            progress(f"skipped {n}/{len(jobs)} {job.name}: it cannot be diagnosed (why: below)")
        else:
            progress(f"diagnosed {n}/{len(jobs)} {job.name}: {headline(outcome.diagnosis)}")
        outcomes.append(outcome)
    return outcomes
